"""Writing and reading ROS 1 / ROS 2 (sqlite3, MCAP) bags through symloc types."""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from symloc.errors import DataFormatError
from symloc.grid import OccupancyGrid
from symloc.io.rosbag import BagTopics, BagWriter, bag_topics, read_bag, resolve_bag_path
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan


def _write_run(path: Path, fmt: str, *, compressed: bool = False, n: int = 5) -> dict:
    rng = np.random.default_rng(3)
    grid = OccupancyGrid(rng.choice(np.array([-1, 0, 100], np.int8), (20, 30)), 0.05)
    scans, odoms, images = [], [], []
    with BagWriter(path, fmt, compressed_images=compressed) as w:
        w.write_map(grid, 0.0)
        for i in range(n):
            t = 1.0 + 0.1 * i
            odo = OdometryReading(np.array([0.1 * i, 0.0, 0.05 * i]), t)
            scan = LaserScan(-math.pi, 2 * math.pi / 100, 0.1, 8.0, rng.uniform(1, 5, 100), stamp=t)
            img = rng.integers(0, 256, (12, 16, 3), dtype=np.uint8)
            w.write_odometry(odo)
            w.write_scan(scan)
            w.write_truth([0.1 * i, 0.02, 0.05 * i], t)
            w.write_image(img, t)
            scans.append(scan)
            odoms.append(odo)
            images.append(img)
        w.write_initialpose([1.0, 2.0, 0.5], np.diag([0.25, 0.25, 0.07]), 2.0)
    return {"grid": grid, "scans": scans, "odoms": odoms, "images": images, "counts": w.counts}


@pytest.mark.parametrize(("fmt", "name"), [("ros2", "run"), ("mcap", "run"), ("ros1", "run.bag")])
def test_bag_round_trip(tmp_path: Path, fmt: str, name: str) -> None:
    path = tmp_path / name
    ref = _write_run(path, fmt)
    msgs = list(read_bag(path))
    kinds = Counter(m.kind for m in msgs)
    assert kinds == {"scan": 5, "odom": 5, "image": 5, "truth": 5, "map": 1, "initialpose": 1}
    scans = [m.value for m in msgs if m.kind == "scan"]
    for got, want in zip(scans, ref["scans"], strict=True):
        np.testing.assert_array_equal(got.ranges, want.ranges.astype(np.float32))
        assert got.stamp == pytest.approx(want.stamp)
    odoms = [m.value for m in msgs if m.kind == "odom"]
    np.testing.assert_allclose([o.pose for o in odoms], [o.pose for o in ref["odoms"]], atol=1e-12)
    imgs = [m.value for m in msgs if m.kind == "image"]
    for got, want in zip(imgs, ref["images"], strict=True):
        np.testing.assert_array_equal(got, want)
    (grid,) = [m.value for m in msgs if m.kind == "map"]
    np.testing.assert_array_equal(grid.data, ref["grid"].data)
    (pc,) = [m.value for m in msgs if m.kind == "initialpose"]
    np.testing.assert_allclose(pc[0], [1.0, 2.0, 0.5], atol=1e-12)
    assert [m.log_time for m in msgs] == sorted(m.log_time for m in msgs)
    topics = bag_topics(path)
    assert topics["/scan"] == ("sensor_msgs/msg/LaserScan", 5)


def test_compressed_images_and_db3_file_path(tmp_path: Path) -> None:
    path = tmp_path / "run"
    ref = _write_run(path, "ros2", compressed=True, n=2)
    db3 = next(path.glob("*.db3"))
    imgs = [m.value for m in read_bag(db3) if m.kind == "image"]
    np.testing.assert_array_equal(imgs[1], ref["images"][1])
    assert "/camera/image_raw/compressed" in bag_topics(path)


def test_malformed_message_names_topic_and_field(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "bad"
    with BagWriter(path) as w:
        w.write_fields(
            "/scan",
            "sensor_msgs/msg/LaserScan",
            {"angle_increment": float("nan"), "range_max": 5.0, "ranges": np.ones(4, np.float32)},
            1.0,
        )
        scan = LaserScan(0.0, 0.1, 0.1, 5.0, np.ones(4), stamp=2.0)
        w.write_scan(scan)
    with pytest.raises(
        DataFormatError, match=r"/scan at log time 1000000000 ns: LaserScan\.angle_increment"
    ):
        list(read_bag(path))
    dropped: Counter[str] = Counter()
    with caplog.at_level("WARNING", logger="symloc.io.rosbag"):
        got = list(read_bag(path, on_error="skip", dropped=dropped))
    (summary,) = (r.getMessage() for r in caplog.records)  # one line for the whole bag
    assert summary.startswith(
        f"bag {path}: skipped 1 undecodable message(s): /scan 1 (first at log time 1.000 s:"
    )
    assert "LaserScan.angle_increment" in summary
    assert len(got) == 1
    assert got[0].stamp == pytest.approx(2.0)
    assert dropped["/scan"] == 1


def test_topic_selection_errors(tmp_path: Path) -> None:
    path = tmp_path / "run"
    _write_run(path, "ros2", n=1)
    with pytest.raises(DataFormatError, match=r"'/laser' for scan not found"):
        list(read_bag(path, topics=BagTopics(scan="/laser")))
    with pytest.raises(DataFormatError, match=r"expected sensor_msgs/msg/LaserScan"):
        list(read_bag(path, topics=BagTopics(scan="odom")))
    msgs = list(read_bag(path, topics=BagTopics(truth=None)))
    assert not any(m.kind == "truth" for m in msgs)


def test_bad_paths(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match="does not exist"):
        resolve_bag_path(tmp_path / "nope.bag")
    with pytest.raises(DataFormatError, match=r"without metadata\.yaml"):
        resolve_bag_path(tmp_path)
    (tmp_path / "x.txt").write_text("hi")
    with pytest.raises(DataFormatError, match="neither a ROS 1"):
        resolve_bag_path(tmp_path / "x.txt")
    (tmp_path / "x.mcap").write_text("hi")
    with pytest.raises(DataFormatError, match=r"no metadata\.yaml beside it"):
        resolve_bag_path(tmp_path / "x.mcap")
    (tmp_path / "junk.bag").write_bytes(b"garbage")
    with pytest.raises(DataFormatError, match="cannot open"):
        list(read_bag(tmp_path / "junk.bag"))
    with pytest.raises(DataFormatError, match="exists already"):
        BagWriter(tmp_path / "junk.bag").open()
    with pytest.raises(DataFormatError, match="fmt: expected"):
        BagWriter(tmp_path / "a", "ros3")  # type: ignore[arg-type]
    with pytest.raises(DataFormatError, match="on_error"):
        list(read_bag(tmp_path / "junk.bag", on_error="ignore"))  # type: ignore[arg-type]


def test_ros2_folder_named_dot_bag(tmp_path: Path) -> None:
    path = tmp_path / "run.bag"  # as `ros2 bag record -o run.bag` names it
    _write_run(path, "ros2", n=2)
    assert path.is_dir()
    assert sum(m.kind == "scan" for m in read_bag(path)) == 2


def test_scans_with_odometry_and_map_from_bag(tmp_path: Path) -> None:
    from symloc.ros.replay import build_map_from_bag, scans_with_odometry

    path = tmp_path / "run"
    ref = _write_run(path, "ros2", n=5)
    scans, odom, dropped = scans_with_odometry(path)
    assert len(scans) == 5
    assert dropped == {}
    np.testing.assert_allclose(odom, [o.pose for o in ref["odoms"]], atol=1e-12)
    empty = tmp_path / "empty"
    with BagWriter(empty) as w:
        w.write_scan(LaserScan(0.0, 0.1, 0.1, 5.0, np.ones(4), stamp=1.0))
    with pytest.raises(DataFormatError, match=r"empty: expected odometry, .* has neither"):
        build_map_from_bag(empty)


SHARED = Path(__file__).resolve().parents[2] / ".." / "shared" / "data"


def _shared_data() -> Path:
    import os

    root = Path(os.environ.get("SYMLOC_SHARED_DATA", SHARED))
    log = root / "carmen" / "aces-corrected.log.gz"
    if not log.is_file():
        pytest.skip(f"shared CARMEN data absent ({log}); set SYMLOC_SHARED_DATA")
    return log


@pytest.mark.shared_data
def test_real_carmen_log_through_a_bag(tmp_path: Path) -> None:
    from symloc.io.carmen import read_carmen
    from symloc.io.rosbag_carmen import carmen_to_bag

    log = _shared_data()
    counts = carmen_to_bag(log, tmp_path / "aces", fmt="mcap")
    ref = read_carmen(log)
    assert counts["/scan"] == len(ref.scans) == 440
    msgs = list(read_bag(tmp_path / "aces"))
    scans = [m.value for m in msgs if m.kind == "scan"]
    odom = np.array([m.value.pose for m in msgs if m.kind == "odom"])
    truth = np.array([m.value.pose for m in msgs if m.kind == "truth"])
    assert len(scans) == 440
    np.testing.assert_allclose(
        scans[100].ranges, ref.scans[100].scan.ranges.astype(np.float32), equal_nan=True
    )
    assert scans[100].angle_min == pytest.approx(ref.scans[100].scan.angle_min, abs=1e-6)
    np.testing.assert_allclose(odom[:, :2], ref.odom_poses[:, :2], atol=1e-9)
    np.testing.assert_allclose(truth[:, :2], ref.laser_poses[:, :2], atol=1e-9)


def test_tf_kinds_and_the_kinds_filter(tmp_path: Path) -> None:
    """/tf and /tf_static come out as lists of transforms, found by name only; ``kinds`` reads
    only the kinds asked for, and an unknown kind is refused by name."""
    path = tmp_path / "tf"
    with BagWriter(path) as w:
        w.write_transforms([("base_link", "laser", (0.2, 0.0, math.pi))], 0.0, static=True)
        w.write_transforms([("odom", "base_link", (1.0, 2.0, 0.5))], 1.0)
        w.write_scan(LaserScan(0.0, 0.1, 0.1, 5.0, np.ones(4), stamp=1.0))
    msgs = list(read_bag(path))
    kinds = [m.kind for m in msgs]
    assert kinds == ["tf_static", "tf", "scan"]
    (t,) = msgs[1].value
    assert (t.parent, t.child, msgs[1].stamp) == ("odom", "base_link", 1.0)
    np.testing.assert_allclose(t.matrix[:2, 3], [1.0, 2.0])
    assert [m.kind for m in read_bag(path, kinds=("scan",))] == ["scan"]
    with pytest.raises(DataFormatError, match=r"kinds: expected some of .* got \['scans'\]"):
        list(read_bag(path, kinds=("scans",)))


def test_offline_pairing_reads_the_laser_mount_and_tf_odometry(tmp_path: Path) -> None:
    """A laser 0.2 m ahead of the base, turned by 90 degrees (/tf_static): the mount is found
    and SLAM is given the laser's odometry; odometry from /tf when the bag has no topic."""
    from symloc.geometry import compose
    from symloc.ros.replay import pair_scans_offline

    path = tmp_path / "mount"
    mount = np.array([0.2, 0.0, math.pi / 2])
    with BagWriter(path) as w:
        w.write_transforms([("base_link", "laser", mount)], 0.0, static=True)
        for i in range(4):
            w.write_transforms([("odom", "base_link", (0.1 * i, 0.0, 0.1 * i))], 1.0 + i)
            w.write_scan(LaserScan(0.0, 0.1, 0.1, 5.0, np.ones(4), stamp=1.0 + i))
    got = pair_scans_offline(path)
    assert got.source == "TF odom -> base_link"
    assert got.laser_frame == "laser"
    np.testing.assert_allclose(got.mount, mount, atol=1e-12)
    np.testing.assert_allclose(got.odometry[:, 0], [0.0, 0.1, 0.2, 0.3], atol=1e-12)
    np.testing.assert_allclose(got.laser_odometry, compose(got.odometry, mount), atol=1e-12)
    with pytest.raises(DataFormatError, match=r"mount: expected odometry on a nav_msgs/Odometry"):
        pair_scans_offline(path, odom_source="topic")
    # the same robot with its odometry on /odom: the mount is read all the same
    topic = tmp_path / "mount_topic"
    with BagWriter(topic) as w:
        w.write_transforms([("base_link", "laser", mount)], 0.0, static=True)
        for i in range(3):
            w.write_odometry(OdometryReading(np.array([0.1 * i, 0.0, 0.0]), 1.0 + i))
            w.write_scan(LaserScan(0.0, 0.1, 0.1, 5.0, np.ones(4), stamp=1.0 + i))
    got = pair_scans_offline(topic, odom_source="topic")
    assert got.source == "topic /odom"
    np.testing.assert_allclose(got.mount, mount, atol=1e-12)
