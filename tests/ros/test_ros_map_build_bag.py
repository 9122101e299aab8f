"""The README's "Your own robot" walkthrough, end to end on bags the test records (issue 28).

A simulated robot drives round a rectangular room of the textured lab (a room the laser alone
cannot tell from its copy turned by 180 degrees) and records what ``ros2 bag record /scan /odom
/tf /tf_static /camera/image_raw`` would: scans, odometry, the static transforms, camera
images, and the simulator's ground truth. ``symloc map build --bag`` maps it (occupancy map,
its own error, keyframes in the visual map); a second drive, started elsewhere with odometry
from zero, is replayed with ``symloc replay --map --visual-map`` on what was built. The robot
must be localized within the claim tolerance (0.1 m, 5 deg) and never confidently wrong.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from symloc.bench.sim_record import MappingDrive, record_mapping_drive
from symloc.bench.slam_metrics import umeyama_se2
from symloc.cli.main import main
from symloc.errors import DataFormatError
from symloc.geometry import compose
from symloc.io.rosbag import BagWriter
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan

CLAIM_XY = 0.1  # [m] the claim tolerance: a pose published as tracking further off is wrong
CLAIM_DEG = 5.0


def _tum(path: Path) -> np.ndarray:
    """(N, 4) t, x, y, theta of a TUM file (planar)."""
    rows = np.loadtxt(path, ndmin=2)
    return np.c_[rows[:, :3], 2.0 * np.arctan2(rows[:, 6], rows[:, 7])]


def _at(truth: np.ndarray, t: float) -> np.ndarray:
    """The (3,) row of ``truth`` (N, 4) nearest in time to ``t``."""
    return np.asarray(truth[int(np.argmin(np.abs(truth[:, 0] - t))), 1:])


def _wall_distance(grid: Any, points: np.ndarray) -> np.ndarray:
    """Distance [m] from each point (P, 2) to the nearest occupied cell of ``grid``."""
    from scipy.spatial import cKDTree

    occ = np.argwhere(grid.data >= 65)
    walls = grid.cell_to_world(occ)
    d, _ = cKDTree(walls).query(points)
    return np.asarray(d)


@pytest.mark.slow
def test_your_own_robot_walkthrough(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from symloc.grid.map_io import load_map, read_map_yaml
    from symloc.vision.visual_map import VisualMap

    # 1. ros2 bag record /scan /odom /tf /tf_static /camera/image_raw (and a ground truth)
    mapping: MappingDrive = record_mapping_drive(tmp_path / "mapping", seed=0, image_every=3)
    assert {"/scan", "/odom", "/tf_static", "/camera/image_raw"} <= set(mapping.counts)

    # 2. symloc map build --bag
    out = tmp_path / "maps"
    assert main(["map", "build", "--bag", str(mapping.bag), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    n_scans = mapping.counts["/scan"]
    assert f"scans: {n_scans} of {n_scans} paired with odometry from topic /odom" in text
    assert "map's own error: std" in text
    assert "map's error place by place: std median" in text
    assert "ATE against ground_truth: RMSE" in text
    for name in ("map.yaml", "map_trajectory.tum", "map_trajectory.png", "map_visual.db"):
        assert (out / name).is_file(), name

    # the map: its walls where the room's walls are (the odometry started at the true start
    # pose, so the map frame is the world frame up to SLAM's error)
    built = load_map(out / "map.yaml")
    field = read_map_yaml(out / "map.yaml").map_error_field
    assert field is not None  # saved with the map, for the claim gate
    assert field.xy.shape[0] >= 3
    occ = built.cell_to_world(np.argwhere(built.data >= 65))
    assert occ.shape[0] > 200
    # (a low-cost lidar's noise thickens the walls outwards: the median and the 90th
    # percentile, not every cell)
    off = _wall_distance(mapping.grid, occ)
    assert float(np.median(off)) < 0.06, "built walls away from the true ones"
    assert float(np.percentile(off, 90)) < 0.2, "built walls away from the true ones"
    # nothing inside the room: the cells 0.3 m or more from every true wall are free
    interior = np.argwhere(built.data >= 0)
    pts = built.cell_to_world(interior)
    inside = (np.abs(pts[:, 0]) < 1.5) & (np.abs(pts[:, 1]) < 0.9)
    cells = interior[inside]
    assert cells.shape[0] > 1000
    occupied_inside = built.data[cells[:, 0], cells[:, 1]] >= 65
    assert occupied_inside.mean() < 0.005, "walls mapped inside the room"
    true_walls = mapping.grid.cell_to_world(np.argwhere(mapping.grid.data >= 65))
    room_walls = true_walls[np.hypot(*true_walls.T) < 2.3]  # the room's walls, not the lab's
    covered = _wall_distance(built, room_walls) < 0.1
    assert covered.mean() > 0.9, f"only {covered.mean():.0%} of the room's walls mapped"
    info = read_map_yaml(out / "map.yaml")
    assert info.map_std_xy is not None
    assert 0.0 < info.map_std_xy < 0.05

    # the keyframes: stored, each at the pose the robot had when it took the image
    slam_traj = _tum(out / "map_trajectory.tum")
    map_from_world = umeyama_se2(
        np.array([_at(mapping.truth, t)[:2] for t in slam_traj[:, 0]]), slam_traj[:, 1:3]
    )
    with VisualMap(out / "map_visual.db", readonly=True) as vm:
        keyframes = vm.keyframes()
        assert vm.get_meta("vocabulary") == "default"
    assert len(keyframes) >= 10
    for kf in keyframes:
        true = np.asarray(compose(map_from_world, _at(mapping.truth, kf.stamp)))
        assert math.hypot(*(kf.pose[:2] - true[:2])) < 0.1
        assert abs(math.degrees(math.remainder(kf.pose[2] - true[2], math.tau))) < 5.0
    n_kf = len(keyframes)
    assert f"visual map: {n_kf} keyframes from" in text

    # 3. symloc replay of another drive on what was built (started elsewhere, odometry from 0)
    drive = record_mapping_drive(
        tmp_path / "drive", seed=1, start_waypoint=2, laps=0.6, odom_at_start=False
    )
    rp = tmp_path / "replay"
    code = main(
        [
            "replay",
            str(drive.bag),
            "--map",
            str(out / "map.yaml"),
            "--visual-map",
            str(out / "map_visual.db"),
            "--out",
            str(rp),
        ]
    )
    text = capsys.readouterr().out
    assert code == 0, text
    assert "recording usable" in text
    # the rectangle's two copies fit the scan: the camera, against the keyframes, decided
    assert "verified by the camera" in text
    tracked = _tum(rp / "replay.tum")
    scans = drive.counts["/scan"]
    assert tracked.shape[0] >= 0.8 * scans, f"{tracked.shape[0]} of {scans} scans tracked"
    errors = []
    for t, x, y, th in tracked:
        true = np.asarray(compose(map_from_world, _at(drive.truth, t)))
        errors.append(
            (
                math.hypot(x - true[0], y - true[1]),
                math.degrees(abs(math.remainder(th - true[2], math.tau))),
            )
        )
    err = np.asarray(errors)
    # never confidently wrong: every pose published as tracking within the claim tolerance
    assert float(err[:, 0].max()) < CLAIM_XY, err[:, 0].max()
    assert float(err[:, 1].max()) < CLAIM_DEG, err[:, 1].max()
    print(
        f"walkthrough: map error {100 * info.map_std_xy:.1f} cm, {n_kf} keyframes; replay"
        f" tracked {tracked.shape[0]} of {scans} scans, error mean {100 * err[:, 0].mean():.1f} cm,"
        f" max {100 * err[:, 0].max():.1f} cm / {err[:, 1].max():.1f} deg"
    )


def test_map_build_bag_with_odometry_on_tf_only(tmp_path: Path) -> None:
    """A robot that publishes its odometry as odom -> base_footprint on /tf only: the map is
    built from TF (the frames found from the transforms), without a visual map when asked."""
    from symloc.ros.bag_mapping import BagMappingSettings, map_from_bag

    drive = record_mapping_drive(tmp_path / "tf", odometry="tf", laps=0.3, image_every=50)
    assert "/odom" not in drive.counts
    assert "/tf" in drive.counts
    got = map_from_bag(drive.bag, settings=BagMappingSettings(visual_map=False))
    assert got.paired.source == "TF odom -> base_footprint"
    assert len(got.paired.scans) == drive.counts["/scan"]
    assert got.keyframes == []
    assert got.image_topic == ""
    np.testing.assert_allclose(got.truth[:, :2], got.poses[:, :2], atol=0.1)
    with pytest.raises(DataFormatError, match=r"tf: expected odometry as wheels -> base"):
        map_from_bag(drive.bag, settings=BagMappingSettings(odom_frame="wheels"))


def test_map_build_bag_errors_name_the_bag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A bag that cannot be mapped: exit 2, one line naming the bag and what was expected."""
    no_scans = tmp_path / "no_scans"
    with BagWriter(no_scans) as w:
        w.write_truth(np.zeros(3), 1.0)
    assert main(["map", "build", "--bag", str(no_scans), "--out", str(tmp_path / "o1")]) == 2
    err = capsys.readouterr().err
    assert f"symloc: error: bag {no_scans}: expected sensor_msgs/LaserScan" in err
    assert "Traceback" not in err

    no_odom = tmp_path / "no_odom"
    with BagWriter(no_odom) as w:
        for i in range(3):
            w.write_scan(LaserScan(0.0, 0.1, 0.1, 5.0, np.ones(4), stamp=1.0 + i))
    assert main(["map", "build", "--bag", str(no_odom), "--out", str(tmp_path / "o2")]) == 2
    err = capsys.readouterr().err
    assert f"bag {no_odom}: expected odometry, on a nav_msgs/Odometry topic or" in err

    few_pairs = tmp_path / "few_pairs"
    with BagWriter(few_pairs) as w:
        for i in range(10):
            if i < 2:
                w.write_odometry(OdometryReading(np.zeros(3), 10.0 * i))
            w.write_scan(LaserScan(0.0, 0.1, 0.1, 5.0, np.ones(4), stamp=10.0 * i))
    assert main(["map", "build", "--bag", str(few_pairs), "--out", str(tmp_path / "o4")]) == 2
    err = capsys.readouterr().err
    assert f"bag {few_pairs}: expected scans with odometry at their stamps" in err
    assert "got 2 (odometry: topic /odom" in err

    missing = tmp_path / "nothing"
    assert main(["map", "build", "--bag", str(missing), "--out", str(tmp_path / "o3")]) == 2
    assert f"{missing} does not exist" in capsys.readouterr().err

    afile = tmp_path / "afile"
    afile.write_text("x")
    with pytest.raises(SystemExit) as exc:  # a usage error, found while parsing
        main(["map", "build", "--bag", str(no_odom), "--out", str(afile)])
    assert exc.value.code == 2
    assert "argument --out: " in capsys.readouterr().err
