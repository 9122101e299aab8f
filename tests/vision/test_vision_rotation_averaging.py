"""Keyframe headings aligned with their images: the planar-motion yaw, the pairs, the robust
1-D rotation averaging (drift, outliers, gauge), the visual map's heading rewrite and the CLI."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from symloc.cli.main import main
from symloc.errors import ConfigurationError, DatabaseError
from symloc.geometry import compose, relative, wrap_angle
from symloc.sim.camera import Camera
from symloc.sim.rooms import build_room
from symloc.vision.bow import BowVector
from symloc.vision.keyframes import Keyframe
from symloc.vision.orb import OrbExtractor, OrbFeatures
from symloc.vision.planar_motion import planar_yaw
from symloc.vision.rotation_averaging import (
    META_KEY,
    HeadingAlignmentSettings,
    align_headings,
    align_map_keyframes,
    candidate_pairs,
    solve_headings,
)
from symloc.vision.two_view import yaw_rotation
from symloc.vision.visual_map import VisualMap

F, W, H = 500.0, 640, 480
K = np.array([[F, 0.0, W / 2], [0.0, F, H / 2], [0.0, 0.0, 1.0]])


def _deg(a: np.ndarray | float) -> np.ndarray:
    return np.degrees(np.asarray(wrap_angle(a)))


# ---------------------------------------------------------------------------- planar motion


def _project(pose: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixels (n, 2) and depths (n,) of world points (x, y, height) from a camera at ``pose``
    (height 0.3 m, looking along theta; image x to the right)."""
    d = pts[:, :2] - pose[:2]
    c, s = math.cos(pose[2]), math.sin(pose[2])
    fwd = c * d[:, 0] + s * d[:, 1]
    left = -s * d[:, 0] + c * d[:, 1]
    uv = np.column_stack([W / 2 - F * left / fwd, H / 2 - F * (pts[:, 2] - 0.3) / fwd])
    return uv, fwd


def _matches(p0: np.ndarray, p1: np.ndarray, noise: float, seed: int = 0) -> tuple[np.ndarray, ...]:
    """Matches between two views of points on a round wall (radius 4 m)."""
    rng = np.random.default_rng(seed)
    a = rng.uniform(-math.pi, math.pi, 20000)
    pts = np.column_stack([4.0 * np.cos(a), 4.0 * np.sin(a), rng.uniform(0.0, 2.0, a.size)])
    (u0, z0), (u1, z1) = _project(p0, pts), _project(p1, pts)
    ok = (z0 > 0.2) & (z1 > 0.2)
    for u in (u0, u1):
        ok &= (u[:, 0] > 0) & (u[:, 0] < W) & (u[:, 1] > 0) & (u[:, 1] < H)
    idx = np.flatnonzero(ok)[:250]
    return (
        u0[idx] + rng.normal(0.0, noise, (idx.size, 2)),
        u1[idx] + rng.normal(0.0, noise, (idx.size, 2)),
    )


def _travel(p0: np.ndarray, p1: np.ndarray) -> float:
    rel = relative(p0, p1)
    t = -yaw_rotation(float(rel[2])) @ np.array([-rel[1], 0.0, rel[0]])
    return math.atan2(t[0], t[2])


#: off the centre of the round wall (at its centre every point is as far: a sideways step
#: looks like a turn)
P0 = np.array([2.5, 0.5, 1.9])


@pytest.mark.parametrize(
    "move",
    [
        np.array([0.0, 0.0, math.radians(12.0)]),  # a pure turn
        np.array([0.4, 0.3, math.radians(-7.0)]),  # sideways and forward
        np.array([0.5, 0.02, math.radians(3.0)]),  # straight ahead
    ],
    ids=["turn", "sideways", "forward"],
)
def test_planar_yaw_is_exact_on_exact_matches(move: np.ndarray) -> None:
    p0 = P0
    p1 = np.asarray(compose(p0, move))
    src, dst = _matches(p0, p1, noise=0.0)
    fit = planar_yaw(src, dst, K, 0.0, math.radians(15.0), direction=_travel(p0, p1),
                     direction_sigma=math.radians(2.0))  # fmt: skip
    assert fit.inliers == src.shape[0]
    assert abs(_deg(fit.yaw - move[2])) < 0.02
    assert fit.sigma < math.radians(0.2)  # a floor of 0.05 px^2 on the residual variance


def test_planar_yaw_with_noise_and_outliers() -> None:
    p0 = P0
    p1 = np.asarray(compose(p0, [0.3, 0.3, math.radians(8.0)]))
    src, dst = _matches(p0, p1, noise=0.5, seed=3)
    dst[:40] = np.random.default_rng(4).uniform([0, 0], [W, H], (40, 2))  # false matches
    fit = planar_yaw(src, dst, K, math.radians(5.0), math.radians(6.0))
    assert abs(_deg(fit.yaw - math.radians(8.0))) < 0.15
    assert src.shape[0] - 40 - 10 <= fit.inliers <= src.shape[0] - 30
    assert fit.sigma < math.radians(0.3)


def test_planar_yaw_refuses_too_few_matches_and_bad_arguments() -> None:
    fit = planar_yaw(np.zeros((3, 2)), np.zeros((3, 2)), K, 0.0, 0.1)
    assert not fit.fitted
    assert fit.sigma == math.inf
    with pytest.raises(ConfigurationError, match="window"):
        planar_yaw(np.zeros((20, 2)), np.zeros((20, 2)), K, 0.0, 0.0)
    with pytest.raises(ConfigurationError, match="src, dst"):
        planar_yaw(np.zeros((20, 2)), np.zeros((21, 2)), K, 0.0, 0.1)


# ---------------------------------------------------------------------------- averaging


#: exact relative headings: weighted as such
EXACT = HeadingAlignmentSettings(measurement_sigma=math.radians(0.02))


def _lap(n: int = 80) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """True headings of two laps turning left, measured pairs (trip neighbours and one lap
    apart) and their exact relative headings."""
    true = np.asarray(wrap_angle(np.linspace(0.0, 4.0 * math.pi, n, endpoint=False)))
    pairs = np.array(
        [(i, i + 1) for i in range(n - 1)]
        + [(i, i + 2) for i in range(n - 2)]
        + [(i, i + n // 2) for i in range(n // 2)]
    )
    yaws = np.asarray(wrap_angle(true[pairs[:, 1]] - true[pairs[:, 0]]))
    return true, pairs, yaws


def test_linear_drift_is_removed_by_exact_relative_headings() -> None:
    true, pairs, yaws = _lap()
    drift = np.radians(np.linspace(-2.0, 2.0, true.size))  # SLAM's, zero mean
    headings, used, rounds = solve_headings(true + drift, pairs, yaws, EXACT)
    assert used.all()
    assert rounds == 1
    assert np.abs(_deg(headings - true)).max() < 0.1
    assert np.abs(_deg(true + drift - true)).max() > 1.9


def test_the_prior_fixes_the_gauge() -> None:
    true, pairs, yaws = _lap()
    # a drift with a mean: the images cannot see the mean, the SLAM headings keep it
    drift = np.radians(np.linspace(0.0, 3.0, true.size))
    headings, _, _ = solve_headings(true + drift, pairs, yaws, EXACT)
    err = _deg(headings - true)
    assert err.max() - err.min() < 0.1
    assert err.mean() == pytest.approx(math.degrees(drift.mean()), abs=0.05)
    # no relative measurement at all: the SLAM headings, unchanged
    prior = true + drift
    alone, used, _ = solve_headings(prior, np.zeros((0, 2), int), np.zeros(0), EXACT)
    assert used.size == 0
    np.testing.assert_allclose(alone, np.asarray(wrap_angle(prior)), atol=1e-9)


def test_an_outlier_pair_is_rejected() -> None:
    true, pairs, yaws = _lap()
    bad = yaws.copy()
    bad[10] += math.radians(5.0)
    drift = np.radians(np.linspace(-2.0, 2.0, true.size))
    headings, used, rounds = solve_headings(true + drift, pairs, bad, EXACT)
    assert np.flatnonzero(~used).tolist() == [10]
    assert rounds >= 2
    assert np.abs(_deg(headings - true)).max() < 0.1


def test_solve_headings_checks_its_inputs() -> None:
    with pytest.raises(ConfigurationError, match="yaws"):
        solve_headings(np.zeros(3), [[0, 1]], [0.1, 0.2])
    with pytest.raises(ConfigurationError, match="pairs"):
        solve_headings(np.zeros(3), [[0, 3]], [0.1])
    with pytest.raises(ConfigurationError, match="sigmas"):
        solve_headings(np.zeros(3), [[0, 1]], [0.1], sigmas=[0.0])
    with pytest.raises(ConfigurationError, match="max_rounds"):
        HeadingAlignmentSettings(max_rounds=0)


def test_candidate_pairs_trip_neighbours_and_loops() -> None:
    # a lap of a 2 m circle facing along it, then the first keyframes again
    a = np.radians(np.arange(0.0, 400.0, 10.0))
    poses = np.column_stack([2 * np.cos(a), 2 * np.sin(a), np.asarray(wrap_angle(a + math.pi / 2))])
    s = HeadingAlignmentSettings(max_distance=0.8, trip_neighbours=2, loop_pairs=2)
    pairs = candidate_pairs(poses, s)
    assert (pairs[:, 0] < pairs[:, 1]).all()
    gaps = pairs[:, 1] - pairs[:, 0]
    assert {(i, i + 1) for i in range(len(a) - 1)} <= {tuple(p) for p in pairs.tolist()}
    loops = pairs[gaps > 2]
    assert len(loops) > 0
    assert (np.abs(gaps[gaps > 2] - 36) <= 2).all()  # one lap apart
    assert np.bincount(loops.ravel()).max() <= 2


# ---------------------------------------------------------------------------- images


SHARP = HeadingAlignmentSettings(measurement_sigma=math.radians(0.05))


def _turn_keyframes(drift_deg: float) -> tuple[list[Keyframe], np.ndarray]:
    """Keyframes of a turn on the spot in a textured round room (every 15 degrees), their SLAM
    headings drifting linearly by ``drift_deg`` in total (zero mean); and the true headings."""
    room = build_room("circle", 2.0, lab=False, textured=True)
    cam, ex = Camera(), OrbExtractor()
    c = np.asarray(room.center, np.float64)
    true = np.radians(np.arange(0.0, 360.0, 15.0))
    drift = np.radians(np.linspace(-drift_deg / 2, drift_deg / 2, true.size))
    kfs = []
    for i, (th, d) in enumerate(zip(true, drift, strict=True)):
        feats = ex.extract(cam.render(room.world, np.array([c[0], c[1], th]), i))
        bow = BowVector(np.array([i], np.int32), np.array([1.0]))
        kfs.append(Keyframe(np.array([c[0], c[1], th + d]), feats, bow, stamp=float(i)))
    return kfs, np.asarray(wrap_angle(true))


def test_align_headings_on_rendered_turn(tmp_path: Path) -> None:
    kfs, true = _turn_keyframes(3.0)
    # a simulated camera turning on the spot: its relative headings are good to ~0.01 degree
    res = align_headings(kfs, Camera().calibration, SHARP)
    before = np.abs(_deg(np.array([k.pose[2] for k in kfs]) - true))
    after = np.abs(_deg(res.headings - true))
    assert before.max() > 1.4
    assert after.max() < 0.3, (res.summary(), after)
    assert res.tied.all()
    aligned = res.apply(kfs)
    np.testing.assert_allclose([k.pose[2] for k in aligned], res.headings)
    np.testing.assert_allclose([k.pose[:2] for k in aligned], [k.pose[:2] for k in kfs])

    # the store keeps them: rewritten in one transaction, read back the same
    path = tmp_path / "vm.sqlite"
    with VisualMap(path) as vm:
        ids = vm.add_keyframes(kfs)
        res2 = align_map_keyframes(vm, Camera().calibration, SHARP)
        np.testing.assert_allclose(res2.headings, res.headings, atol=1e-9)
        assert "keyframe headings:" in (vm.get_meta(META_KEY) or "")
    with VisualMap(path, readonly=True) as vm:
        got_ids, poses = vm.keyframe_poses()
        assert got_ids.tolist() == ids
        np.testing.assert_allclose(poses[:, 2], res.headings, atol=1e-12)
        np.testing.assert_allclose(poses[:, :2], [k.pose[:2] for k in kfs])


def test_set_keyframe_headings_is_all_or_nothing(tmp_path: Path) -> None:
    feats = OrbFeatures.from_arrays(np.zeros((0, 6), np.float32), np.zeros((0, 32), np.uint8),
                                    (W, H))  # fmt: skip
    bow = BowVector(np.array([1], np.int32), np.array([1.0]))
    with VisualMap(tmp_path / "vm.sqlite") as vm:
        ids = vm.add_keyframes(
            [Keyframe(np.array([i, 0.0, 0.1 * i]), feats, bow) for i in range(3)]
        )
        with pytest.raises(DatabaseError, match="no keyframe with id"):
            vm.set_keyframe_headings([ids[0], ids[1], 999], [1.0, 2.0, 3.0])
        np.testing.assert_allclose(vm.keyframe_poses()[1][:, 2], [0.0, 0.1, 0.2])
        with pytest.raises(ConfigurationError, match="headings"):
            vm.set_keyframe_headings(ids, [1.0, math.nan, 2.0])
        vm.set_keyframe_headings(ids[::-1], [4.0, 1.0, 2.0], meta={"k": "v"})
        np.testing.assert_allclose(
            vm.keyframe_poses()[1][:, 2], np.asarray(wrap_angle([2.0, 1.0, 4.0]))
        )
        assert vm.get_meta("k") == "v"


def test_cli_align_keyframes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    kfs, true = _turn_keyframes(3.0)
    db = tmp_path / "vm.sqlite"
    with VisualMap(db) as vm:
        vm.add_keyframes(kfs)
    hfov = f"{math.degrees(Camera().hfov):.6f}"
    cmd = ["places", "align-keyframes", "--db", str(db), "--hfov", hfov]
    cmd += ["--measurement-sigma", "0.05"]
    assert main([*cmd, "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert "dry run: nothing written" in out
    with VisualMap(db, readonly=True) as vm:
        np.testing.assert_allclose(vm.keyframe_poses()[1][:, 2], [k.pose[2] for k in kfs])
    assert main(cmd) == 0
    assert "headings rewritten" in capsys.readouterr().out
    with VisualMap(db, readonly=True) as vm:
        err = np.abs(_deg(vm.keyframe_poses()[1][:, 2] - true))
    assert err.max() < 0.3
