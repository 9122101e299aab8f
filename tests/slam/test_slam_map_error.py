"""The map's own error (:mod:`symloc.slam.map_error`): small where the scans that drew the map
agree, large where part of the trip was drawn a few centimetres off; SLAM moves its map so a
scan aligned to it lands where SLAM put it; the estimate reaches the claim gate through the
map's YAML and the node."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from conftest import raycast, room_segments
from symloc.errors import MapFileError
from symloc.grid import OccupancyGrid
from symloc.grid.log_odds import LogOddsGrid
from symloc.grid.map_io import read_map_yaml, save_map
from symloc.localizer.build import build_localizer
from symloc.localizer.settings import LocalizerSettings
from symloc.scan import LaserScan
from symloc.slam import run_slam
from symloc.slam.map_error import estimate_map_error

ROOM = room_segments()


def _scan(pose: np.ndarray, rng: np.random.Generator) -> LaserScan:
    n = 720
    angles = -math.pi + 2 * math.pi * np.arange(n) / n
    r = raycast(ROOM, pose, angles, 12.0) + rng.normal(0.0, 0.01, n)
    return LaserScan(-math.pi, 2 * math.pi / n, 0.1, 12.0, r)


def _poses(rng: np.random.Generator, n: int) -> np.ndarray:
    """Poses in the room's open middle (clear of the inner walls)."""
    return np.column_stack(
        [rng.uniform(1.5, 4.5, n), rng.uniform(2.0, 3.8, n), rng.uniform(-math.pi, math.pi, n)]
    )


def _drawn(scans: list[LaserScan], at: np.ndarray) -> OccupancyGrid:
    """The map ``scans`` draw at the poses ``at`` (N, 3)."""
    grid = LogOddsGrid(0.05, origin_xy=(0.0, 0.0), clamp=False)
    for p, s in zip(at, scans, strict=True):
        grid.integrate(p, s)
    return grid.to_occupancy_grid(crop_margin=10)


def test_scans_that_agree_give_a_small_error() -> None:
    rng = np.random.default_rng(3)
    poses = _poses(rng, 30)
    scans = [_scan(p, rng) for p in poses]
    err = estimate_map_error(_drawn(scans, poses), scans, poses)
    assert err is not None
    assert err.nodes == 30
    assert err.std_xy < 0.006
    # the quantisation shift all scans share is reported, not counted as error
    assert np.hypot(*err.shift) < 0.05


def test_a_part_of_the_trip_drawn_off_gives_a_large_error() -> None:
    rng = np.random.default_rng(4)
    poses = _poses(rng, 30)
    scans = [_scan(p, rng) for p in poses]
    # SLAM put the last third of the trip 8 cm off: the map holds both copies of the walls
    slam = poses.copy()
    slam[20:, :2] += [0.08, -0.03]
    err = estimate_map_error(_drawn(scans, slam), scans, slam)
    assert err is not None
    assert err.std_xy > 0.02  # above the claim gate's default map error
    assert err.p95_xy > 0.04


def test_too_few_usable_scans_give_no_estimate() -> None:
    rng = np.random.default_rng(5)
    poses = _poses(rng, 2)
    scans = [_scan(p, rng) for p in poses]
    assert estimate_map_error(_drawn(scans, poses), scans, poses) is None
    with pytest.raises(ValueError, match="one per scan"):
        estimate_map_error(_drawn(scans, poses), scans, poses[:1])


def test_slam_moves_its_map_onto_its_poses_and_writes_the_error(tmp_path: Path) -> None:
    rng = np.random.default_rng(6)
    t = np.linspace(0.0, 1.0, 60)
    truth = np.column_stack([1.5 + 3.0 * t, 2.0 + 1.5 * t, 0.3 + 2.0 * t])
    scans = [_scan(p, rng) for p in truth]
    res = run_slam(scans, truth, progress=False)
    assert res.map_error is not None
    assert res.map_error.std_xy < 0.01
    # aligned again to the map SLAM returns, its scans no longer share a shift
    again = estimate_map_error(
        res.grid, [scans[i] for i in res.node_scans], res.poses[res.node_scans]
    )
    assert again is not None
    assert np.hypot(*again.shift) < 0.005
    path = save_map(res.grid, tmp_path / "m", extra=res.map_metadata())
    assert read_map_yaml(path).map_std_xy == pytest.approx(res.map_error.std_xy, abs=1e-4)


def test_map_yaml_map_error_is_validated(tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    poses = _poses(rng, 5)
    grid = _drawn([_scan(p, rng) for p in poses], poses)
    plain = save_map(grid, tmp_path / "plain")
    assert read_map_yaml(plain).map_std_xy is None
    bad = save_map(grid, tmp_path / "bad", extra={"symloc_slam": {"map_error": {"std_xy": -1}}})
    with pytest.raises(MapFileError, match=r"symloc_slam\.map_error\.std_xy"):
        read_map_yaml(bad)


def test_claim_gate_takes_the_larger_map_error() -> None:
    rng = np.random.default_rng(8)
    poses = _poses(rng, 5)
    grid = _drawn([_scan(p, rng) for p in poses], poses)
    settings = LocalizerSettings()
    default = settings.claim.map_std_xy
    for given, want in ((None, default), (0.005, default), (0.06, 0.06)):
        loc = build_localizer(grid, settings, map_std_xy=given)
        gate = loc.claim_gate
        assert gate is not None
        assert gate.config.map_std_xy == pytest.approx(want)


def test_the_map_error_runs_without_the_compiled_kernels(monkeypatch: pytest.MonkeyPatch) -> None:
    """By default the map error aligns in NumPy (a mapping process need not load numba, ~120
    MB): the same estimate as the localizer's compiled look-ups."""
    from symloc.mcl import kernels
    from symloc.mcl.scan_to_map import ScanMatchConfig

    rng = np.random.default_rng(3)
    poses = _poses(rng, 12)
    scans = [_scan(p, rng) for p in poses]
    grid = _drawn(scans, poses)
    compiled = estimate_map_error(grid, scans, poses, config=ScanMatchConfig())

    def _refuse(*args: object) -> None:
        raise AssertionError("the map error used a compiled kernel")

    monkeypatch.setattr(kernels, "bilinear", _refuse)
    monkeypatch.setattr(kernels, "squared_distance_sum", _refuse)
    plain = estimate_map_error(grid, scans, poses)
    assert compiled is not None
    assert plain is not None
    assert np.array_equal(plain.moves, compiled.moves)
    assert np.array_equal(plain.shift, compiled.shift)
