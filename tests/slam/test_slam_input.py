"""SLAM's input is one whether a CARMEN log is read as text or through its ROS bag (issue 28).

``symloc map build --carmen`` used to give SLAM the log's scans in float64 and its odometry
headings as drawn; ``symloc replay BAG --build-map`` gives it the same scans as
sensor_msgs/LaserScan holds them (float32) and the headings after a round trip through a
quaternion (5e-16 rad off), and used to drop the scans whose stamps go backwards. SLAM's
decisions turn on such perturbations, so the CARMEN reader gives scans at float32 precision,
:func:`symloc.slam.slam.slam_input` rounds the headings to a grid and ``carmen-to-bag`` stamps
a backward scan after its predecessor.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from symloc.bench.slam_runs import map_build_odometry
from symloc.geometry import wrap_angle
from symloc.io.carmen import read_carmen
from symloc.io.rosbag_carmen import carmen_to_bag, ordered_stamps
from symloc.msgs.fields import quaternion_from_yaw, yaw_from_quaternion
from symloc.ros.replay import pair_scans_offline
from symloc.slam.slam import ODOMETRY_HEADING_STEP, slam_input

FIELDS = ("angle_min", "angle_increment", "range_min", "range_max", "time_increment", "scan_time")


def _carmen(path: Path, scans: int = 40, backwards: int = 17) -> Path:
    """A corrected CARMEN log with millimetre ranges (not float32 values), a robot that drives
    and turns through +-pi, and the stamp of scan ``backwards`` 0.3 s before its predecessor's
    (intel's clock glitches)."""
    rng = np.random.default_rng(11)
    lines = []
    for i in range(scans):
        ranges = " ".join(f"{r:.3f}" for r in rng.uniform(0.3, 49.0, 181))
        pose = f"{0.25 * i:.4f} {0.1 * math.sin(i):.4f} {math.remainder(0.37 * i, 2 * math.pi):.6f}"
        t = 1_000_000_000.0 + 0.5 * i - (0.8 if i == backwards else 0.0)
        lines.append(f"FLASER 181 {ranges} {pose} {pose} {t:.6f} host {t:.6f}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_carmen_log_and_its_bag_give_slam_one_input(tmp_path: Path) -> None:
    log_path = _carmen(tmp_path / "tiny-corrected.log")
    log = read_carmen(log_path)
    odom = map_build_odometry(log, "tiny", "realistic", 0)
    notes: list[str] = []
    carmen_to_bag(log_path, tmp_path / "bag", odometry=odom, notes=notes)
    assert any("1 scan(s) stamped at or before" in n for n in notes), notes
    got = pair_scans_offline(tmp_path / "bag")
    assert len(got.scans) == len(log.scans) == 40
    assert got.dropped == {}
    carmen_scans = [s.scan for s in log.scans]
    # the log's millimetres as float64 would not be the bag's float32 values
    text = np.array((log_path.read_text().splitlines()[3]).split()[2:183], dtype=np.float64)
    assert not np.array_equal(text, got.scans[3].ranges)
    np.testing.assert_array_equal(text.astype(np.float32), carmen_scans[3].ranges)
    a_scans, a_odom = slam_input(carmen_scans, odom)
    b_scans, b_odom = slam_input(got.scans, got.laser_odometry)
    np.testing.assert_array_equal(a_odom, b_odom)
    for a, b in zip(a_scans, b_scans, strict=True):
        np.testing.assert_array_equal(a.ranges, b.ranges)
        np.testing.assert_array_equal(a.angles, b.angles)
        assert [getattr(a, f) for f in FIELDS] == [getattr(b, f) for f in FIELDS]


def test_odometry_headings_survive_a_quaternion() -> None:
    """A heading read back from the quaternion it was written as is often 1 ulp off; on
    SLAM's heading grid the two are one value. Positions are kept as given."""
    rng = np.random.default_rng(2)
    odom = np.column_stack([rng.uniform(-50, 50, (5000, 2)), rng.uniform(-4, 4, 5000)])
    back = odom.copy()
    back[:, 2] = [
        yaw_from_quaternion(SimpleNamespace(**quaternion_from_yaw(y)), "q") for y in odom[:, 2]
    ]
    off = wrap_angle(back[:, 2] - odom[:, 2])
    assert np.count_nonzero(off) > 0
    assert np.abs(off).max() < 1e-15
    _, a = slam_input([], odom)
    _, b = slam_input([], back)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a[:, :2], odom[:, :2])
    assert np.abs(wrap_angle(a[:, 2] - odom[:, 2])).max() <= ODOMETRY_HEADING_STEP
    np.testing.assert_array_equal(np.round(a[:, 2] / ODOMETRY_HEADING_STEP) % 1, 0.0)
    assert odom[0, 2] != a[0, 2]  # the caller's array is not changed
    odom_copy = odom.copy()
    slam_input([], odom)
    np.testing.assert_array_equal(odom, odom_copy)


def test_ordered_stamps_moves_only_the_stamps_that_go_backwards() -> None:
    poses = np.array([[0, 0, 0], [1, 0, 0], [1, 0, math.pi / 2], [1.5, 0, math.pi / 2], [2, 0, 0]])
    t, moved = ordered_stamps([10.0, 11.0, 10.9, 10.9, 20.0], poses)
    # 10.9 after 11.0: a quarter turn at 90 deg/s, 1 s; then 0.5 m at 0.5 m/s, 1 s
    np.testing.assert_allclose(t, [10.0, 11.0, 12.0, 13.0, 20.0])
    assert moved == 2
    same, none = ordered_stamps([1.0, 2.0, 3.0], poses[:3])
    assert none == 0
    assert same.tolist() == [1.0, 2.0, 3.0]
    with pytest.raises(Exception, match="expected 3 poses"):
        ordered_stamps([1.0, 2.0, 3.0], poses)
