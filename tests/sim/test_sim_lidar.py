"""Ray casting and the simulated lidar."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.sim.lidar import (
    LDS01,
    PAPER_15M,
    PRESETS,
    RPLIDAR_A2,
    LidarPreset,
    raycast,
    simulate_scan,
)
from symloc.sim.raycast import ray_intersections
from symloc.sim.rooms import build_room, circular_room
from symloc.sim.world import World, polygon_walls

SQUARE = World(polygon_walls([[-2, -2], [2, -2], [2, 2], [-2, 2]]), wall_heights=2.5)


def test_raycast_square_hand_computed() -> None:
    origin = np.array([0.5, -1.0])
    angles = np.array([0.0, math.pi / 2, math.pi, -math.pi / 2, math.pi / 4, math.atan2(3, 1.5)])
    r = raycast(SQUARE, origin, angles)
    # +x: wall x=2 -> 1.5; +y: y=2 -> 3; -x: x=-2 -> 2.5; -y: y=-2 -> 1.0
    # 45 deg: hits x=2 at y=0.5 -> 1.5*sqrt(2); toward corner (2, 2): sqrt(1.5^2 + 3^2)
    expected = [1.5, 3.0, 2.5, 1.0, 1.5 * math.sqrt(2), math.hypot(1.5, 3.0)]
    assert np.allclose(r, expected, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    x=st.floats(-1.99, 1.99),
    y=st.floats(-1.99, 1.99),
    theta=st.floats(-math.pi, math.pi),
)
def test_raycast_inside_box_property(x: float, y: float, theta: float) -> None:
    """From inside the 4 m box, the range is the nearest positive crossing of x = +-2, y = +-2."""
    d = np.array([math.cos(theta), math.sin(theta)])
    with np.errstate(divide="ignore"):
        tx = np.max((np.array([-2.0, 2.0]) - x) / d[0]) if abs(d[0]) > 1e-12 else np.inf
        ty = np.max((np.array([-2.0, 2.0]) - y) / d[1]) if abs(d[1]) > 1e-12 else np.inf
    r = raycast(SQUARE, [x, y], [theta])[0]
    assert r == pytest.approx(min(tx, ty), rel=1e-9, abs=1e-9)


def test_raycast_broadcasts_over_origins() -> None:
    origins = np.array([[0.0, 0.0], [1.0, 1.0]])
    angles = np.array([[0.0, math.pi / 2], [math.pi, -math.pi / 2]])
    r = raycast(SQUARE, origins, angles)
    assert np.allclose(r, [[2.0, 2.0], [3.0, 3.0]])
    r2 = raycast(SQUARE, origins, np.array([0.0, math.pi]))
    assert r2.shape == (2, 2)
    assert np.allclose(r2, [[2.0, 2.0], [1.0, 3.0]])


def test_raycast_misses_give_inf_and_heights_filter() -> None:
    wall = World(walls=[[1, -1, 1, 1]], wall_heights=0.4)
    r = raycast(wall, [0, 0], [0.0, math.pi])
    assert r[0] == pytest.approx(1.0)
    assert np.isinf(r[1])
    assert np.isinf(raycast(wall, [0, 0], [0.0], min_height=0.5)[0])


def test_raycast_circles_inside_and_outside() -> None:
    w = World(circles=[[0, 0, 3.0], [1.5, 0, 0.5]], circle_heights=2.0)
    r = raycast(w, [0, 0], [0.0, math.pi, math.pi / 2])
    assert np.allclose(r, [1.0, 3.0, 3.0])
    room = circular_room(2.0, center=(1.0, 1.0))
    rr = raycast(room.world, [1.5, 1.0], np.linspace(0, 2 * np.pi, 90, endpoint=False))
    hits = np.array([1.5, 1.0]) + rr[:, None] * np.column_stack(
        [
            np.cos(np.linspace(0, 2 * np.pi, 90, endpoint=False)),
            np.sin(np.linspace(0, 2 * np.pi, 90, endpoint=False)),
        ]
    )
    assert np.allclose(np.hypot(hits[:, 0] - 1, hits[:, 1] - 1), 2.0)


def test_ray_intersections_lists_every_hit() -> None:
    w = World(walls=[[1, -1, 1, 1], [3, -1, 3, 1]], wall_heights=[0.4, 2.5])
    hits = ray_intersections(w, [0, 0], [0.0])
    assert np.allclose(hits.t[0], [1.0, 3.0])
    assert np.allclose(hits.s[0], [1.0, 1.0])
    assert np.allclose(hits.heights, [0.4, 2.5])


def test_lidar_sees_boards_not_lab_in_paper_room() -> None:
    room = build_room("square", 1.5 * math.sqrt(2))
    scan = simulate_scan(room.world, [0, 0, 0], RPLIDAR_A2, 0, noise=False)
    pts = scan.to_points().points
    assert np.all(np.max(np.abs(pts), axis=1) <= 1.5 + 1e-9)
    assert np.allclose(np.max(np.abs(pts), axis=1), 1.5)
    # with the lidar above the boards it sees the lab instead
    high = simulate_scan(room.world, [0, 0, 0], RPLIDAR_A2, 0, noise=False, mount_height=0.5)
    assert np.min(high.ranges) >= 4.0 - 1e-9


def test_scan_pose_rotates_beams() -> None:
    scan = simulate_scan(SQUARE, [1.0, 0.0, math.pi / 2], PAPER_15M, noise=False)
    assert scan.ranges[0] == pytest.approx(2.0)  # beam 0 looks along world +y
    assert scan.ranges[90] == pytest.approx(3.0)  # beam 90 (90 deg) along world -x
    assert len(scan) == 360
    assert scan.angle_increment == pytest.approx(math.radians(1.0))


def test_no_return_is_inf_and_too_close_is_minus_inf() -> None:
    w = World(walls=[[0.05, -0.1, 0.05, 0.1], [-10, -1, -10, 1]])
    scan = simulate_scan(w, [0, 0, 0], LDS01, noise=False)
    assert scan.ranges[0] == -np.inf  # 5 cm < range_min 0.12 m
    assert scan.ranges[180] == np.inf  # 10 m > range_max 3.5 m
    assert np.isinf(scan.ranges[90])  # nothing at all
    assert scan.invalid_mask[0]
    assert scan.no_return_mask[180]


@pytest.mark.parametrize("preset", list(PRESETS.values()), ids=list(PRESETS))
def test_noise_statistics_match_data_sheet(preset: LidarPreset) -> None:
    rng = np.random.default_rng(1)
    big = World(polygon_walls([[-1, -1], [1, -1], [1, 1], [-1, 1]]))
    ranges_true: list[np.ndarray] = []
    ranges_meas: list[np.ndarray] = []
    for x in np.linspace(-0.7, 0.7, 5):
        pose = [x, 0.3 * x, 0.1]
        exact = simulate_scan(big, pose, preset, noise=False).ranges
        for _ in range(40):
            ranges_meas.append(simulate_scan(big, pose, preset, rng).ranges)
            ranges_true.append(exact)
    t = np.concatenate(ranges_true)
    m = np.concatenate(ranges_meas)
    ok = np.isfinite(m) & np.isfinite(t)
    err = (m - t)[ok]
    sig = preset.sigma(t[ok])
    z = err / sig
    assert abs(np.mean(z)) < 0.05
    assert np.std(z) == pytest.approx(1.0, rel=0.05)
    # the data-sheet figure itself: the accuracy band maps to sigma_fraction x band
    checked = 0
    for lo, hi in [(0.2, 0.5), (0.5, 1.0), (1.0, 1.5)]:
        sel = (t[ok] >= lo) & (t[ok] < hi)
        if sel.sum() < 2000:
            continue
        checked += 1
        band = preset.accuracy(t[ok][sel])
        measured = np.sqrt(np.mean(err[sel] ** 2))
        expected = preset.sigma_fraction * np.sqrt(np.mean(band**2))
        assert measured == pytest.approx(expected, rel=0.2)
    assert checked >= 2


def test_data_sheet_figures() -> None:
    assert LDS01.accuracy([0.3])[0] == pytest.approx(0.010)
    assert LDS01.accuracy([2.0])[0] == pytest.approx(0.07)
    assert LDS01.sigma([2.0])[0] == pytest.approx(0.035)
    assert (LDS01.n_beams, LDS01.range_min, LDS01.range_max) == (360, 0.12, 3.5)
    assert RPLIDAR_A2.n_beams == 800
    assert RPLIDAR_A2.range_max == 16.0
    assert math.degrees(RPLIDAR_A2.angle_increment) == pytest.approx(0.45)
    assert RPLIDAR_A2.accuracy([10.0])[0] == pytest.approx(0.1)
    assert PAPER_15M.sigma([14.0])[0] == pytest.approx(0.01)
    assert PAPER_15M.range_max == 15.0
    for p in PRESETS.values():
        assert p.source


def test_dropout_rate() -> None:
    rng = np.random.default_rng(3)
    preset = RPLIDAR_A2.with_(dropout_rate=0.07)
    n = 0
    nan = 0
    for _ in range(30):
        s = simulate_scan(SQUARE, [0.2, 0.1, 0.0], preset, rng)
        nan += int(np.isnan(s.ranges).sum())
        n += len(s)
    assert nan / n == pytest.approx(0.07, rel=0.1)
    s = simulate_scan(SQUARE, [0, 0, 0], RPLIDAR_A2, rng, dropout_rate=0.5)
    assert 300 < np.isnan(s.ranges).sum() < 500
    assert s.to_points().n_invalid == np.isnan(s.ranges).sum()
    assert not np.isnan(simulate_scan(SQUARE, [0, 0, 0], preset, rng, noise=False).ranges).any()


def test_seeded_scans_repeat() -> None:
    a = simulate_scan(SQUARE, [0, 0, 0], LDS01, 5).ranges
    b = simulate_scan(SQUARE, [0, 0, 0], LDS01, 5).ranges
    c = simulate_scan(SQUARE, [0, 0, 0], LDS01, 6).ranges
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_preset_validation() -> None:
    with pytest.raises(ConfigurationError, match="n_beams: expected an integer >= 3"):
        LDS01.with_(n_beams=2)
    with pytest.raises(ConfigurationError, match="range_min < range_max"):
        LDS01.with_(range_min=5.0)
    with pytest.raises(ConfigurationError, match="dropout_rate: expected a value in"):
        LDS01.with_(dropout_rate=1.0)
    with pytest.raises(ConfigurationError, match="sigma_fraction"):
        LDS01.with_(sigma_fraction=0.0)
    with pytest.raises(ConfigurationError, match="accuracy_abs, accuracy_rel"):
        LDS01.with_(accuracy_rel=-0.1)
    with pytest.raises(ConfigurationError, match="scan_rate"):
        LDS01.with_(scan_rate=0.0)
    with pytest.raises(ConfigurationError, match="dropout_rate"):
        simulate_scan(SQUARE, [0, 0, 0], LDS01, 0, dropout_rate=1.5)
