"""The lidar fault model: each fault changes the statistic it should and nothing else."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.bench.stats import wilson_interval
from symloc.errors import ConfigurationError
from symloc.sim.lidar import (
    LDS01,
    RPLIDAR_A2,
    LidarFaults,
    SimulatedLidar,
    beam_poses,
    raycast,
    simulate_scan,
)
from symloc.sim.raycast import raycast_nearest
from symloc.sim.world import (
    MATERIAL_DARK,
    MATERIAL_FURNITURE,
    MATERIAL_GLASS,
    MATERIAL_PERSON,
    MATERIAL_WALL,
    World,
    polygon_walls,
)

SQUARE = World(polygon_walls([[-2, -2], [2, -2], [2, 2], [-2, 2]]), wall_heights=2.5)
# the data sheet's beams and timing without range noise: every fault shows on its own
EXACT = RPLIDAR_A2.with_(name="exact", accuracy_rel=0.0)


def _inside(lo: float, hi: float, k: int, n: int) -> bool:
    a, b = wilson_interval(k, n)
    return a <= hi and lo <= b


def test_no_faults_draws_the_same_scans_as_simulate_scan() -> None:
    for preset in (LDS01, RPLIDAR_A2.with_(dropout_rate=0.03)):
        a = simulate_scan(SQUARE, [0.3, -0.2, 0.4], preset, 7)
        b = SimulatedLidar(preset, LidarFaults(), 7).scan(SQUARE, [0.3, -0.2, 0.4])
        assert np.array_equal(a.ranges, b.ranges, equal_nan=True)
        # no simulated skew: every beam from the stamp's pose, and the scan says so
        assert a.time_increment == b.time_increment == 0.0
        skewed = SimulatedLidar(preset, LidarFaults(motion_skew=True), 7).scan(
            SQUARE, [0.3, -0.2, 0.4], twist=(0.2, 0.5)
        )
        assert skewed.time_increment == pytest.approx(1.0 / preset.scan_rate / preset.n_beams)


def test_raycast_nearest_reports_material_incidence_and_primitive() -> None:
    w = World(
        walls=[[1, -1, 1, 1], [3, -5, 3, 5]],
        wall_materials=[MATERIAL_GLASS, MATERIAL_WALL],
        circles=[[-2, 0, 0.5]],
        circle_materials=MATERIAL_FURNITURE,
        circle_heights=1.0,
    )
    h = raycast_nearest(w, [0, 0], [0.0, math.pi / 4, math.pi, math.pi / 2])
    assert np.allclose(h.ranges[:3], [1.0, math.sqrt(2), 1.5])
    assert np.isinf(h.ranges[3])
    assert list(h.materials) == [MATERIAL_GLASS, MATERIAL_GLASS, MATERIAL_FURNITURE, -1]
    assert list(h.primitives) == [0, 0, 2, -1]
    assert np.allclose(h.cos_incidence[:3], [1.0, math.cos(math.pi / 4), 1.0])
    behind = raycast_nearest(w, [0, 0], [0.0], skip_materials=(MATERIAL_GLASS,))
    assert behind.ranges[0] == pytest.approx(3.0)
    assert behind.primitives[0] == 1
    assert np.allclose(raycast(w, [0, 0], [0.0, math.pi]), [1.0, 1.5])


def test_dropout_rate_within_its_wilson_interval_and_nothing_else_changes() -> None:
    lidar = SimulatedLidar(EXACT, LidarFaults(dropout_rate=0.05), 1)
    exact = simulate_scan(SQUARE, [0.2, 0.1, 0.3], EXACT, noise=False).ranges
    nan = total = 0
    for _ in range(40):
        r = lidar.scan(SQUARE, [0.2, 0.1, 0.3]).ranges
        bad = np.isnan(r)
        nan += int(bad.sum())
        total += r.size
        assert np.array_equal(r[~bad], exact[~bad])
    assert _inside(0.05, 0.05, nan, total)
    assert not _inside(0.04, 0.04, nan, total)


def test_range_bias_is_drawn_once_per_unit() -> None:
    faults = LidarFaults(range_bias_std=0.01, range_scale_std=0.02)
    exact = simulate_scan(SQUARE, [0, 0, 0], EXACT, noise=False).ranges
    offsets, scales = [], []
    for seed in range(300):
        lidar = SimulatedLidar(EXACT, faults, seed)
        a = lidar.scan(SQUARE, [0, 0, 0]).ranges
        b = lidar.scan(SQUARE, [0, 0, 0]).ranges
        assert np.array_equal(a, b)  # the same unit repeats its error
        assert np.allclose(a, exact * (1 + lidar.range_scale) + lidar.range_offset)
        offsets.append(lidar.range_offset)
        scales.append(lidar.range_scale)
    assert abs(np.mean(offsets)) < 3 * 0.01 / math.sqrt(300)
    assert np.std(offsets) == pytest.approx(0.01, rel=0.15)
    assert np.std(scales) == pytest.approx(0.02, rel=0.15)


def test_angular_jitter_has_the_stated_spread() -> None:
    faults = LidarFaults(angle_jitter_bins=1.0)
    lidar = SimulatedLidar(EXACT, faults, 3)
    a = EXACT.angles
    sel = (a > 0.2) & (a < 0.6)  # these beams hit the wall x = 2 from the origin
    errs = []
    for _ in range(30):
        r = lidar.scan(SQUARE, [0, 0, 0]).ranges[sel]
        true_angle = np.arccos(np.clip(2.0 / r, -1, 1))
        errs.append(true_angle - a[sel])
    e = np.concatenate(errs)
    assert abs(np.mean(e)) < 3 * EXACT.angle_increment / math.sqrt(e.size)
    assert np.std(e) == pytest.approx(EXACT.angle_increment, rel=0.1)


GLASS_ROOM = World(
    walls=[[1.0, -3.0, 1.0, 3.0], [3.0, -6.0, 3.0, 6.0]],
    wall_materials=[MATERIAL_GLASS, MATERIAL_WALL],
)


def test_glass_is_mostly_invisible_and_reflects_only_near_its_normal() -> None:
    faults = LidarFaults(
        glass_reflect_angle=math.radians(10.0), glass_reflect_prob=0.7, glass_no_return_prob=0.2
    )
    lidar = SimulatedLidar(EXACT, faults, 5)
    a = np.asarray(EXACT.angles)
    a = np.where(a > math.pi, a - 2 * math.pi, a)
    cone = np.abs(a) < math.radians(9.5)
    outside = (np.abs(a) > math.radians(10.5)) & (np.abs(a) < math.radians(60))
    seen_cone = seen_out = lost_out = behind_out = 0
    n_cone = n_out = 0
    for _ in range(60):
        r = lidar.scan(GLASS_ROOM, [0, 0, 0]).ranges
        on_glass = np.isclose(r, 1.0 / np.cos(a), rtol=1e-9)
        on_back = np.isclose(r, 3.0 / np.cos(a), rtol=1e-9)
        seen_cone += int(on_glass[cone].sum())
        n_cone += int(cone.sum())
        seen_out += int(on_glass[outside].sum())
        lost_out += int(np.isposinf(r[outside]).sum())
        behind_out += int(on_back[outside].sum())
        n_out += int(outside.sum())
    assert _inside(0.7, 0.7, seen_cone, n_cone)
    assert seen_out == 0
    assert _inside(0.2, 0.2, lost_out, n_out)
    assert lost_out + behind_out == n_out
    # by default glass is seen like a wall (today's behaviour)
    r = SimulatedLidar(EXACT, LidarFaults(), 0).scan(GLASS_ROOM, [0, 0, 0]).ranges
    assert r[0] == pytest.approx(1.0)


def test_dark_surfaces_return_less_with_range_and_incidence() -> None:
    r50 = 0.4 * EXACT.range_max
    faults = LidarFaults(dark_range_fraction=0.4, dark_spread=0.5)
    lidar = SimulatedLidar(EXACT, faults, 9)

    def miss_rate(world: World, sel: np.ndarray | None = None) -> tuple[int, int]:
        miss = n = 0
        for _ in range(20):
            r = lidar.scan(world, [0, 0, 0]).ranges
            r = r if sel is None else r[sel]
            miss += int(np.isposinf(r).sum())
            n += r.size
        return miss, n

    # a round dark room of radius r50 around the sensor: head-on everywhere, half are lost
    at_r50 = World(circles=[[0, 0, r50]], circle_materials=MATERIAL_DARK, circle_heights=2.0)
    assert _inside(0.5, 0.5, *miss_rate(at_r50))
    near = World(circles=[[0, 0, 0.3 * r50]], circle_materials=MATERIAL_DARK, circle_heights=2.0)
    far = World(circles=[[0, 0, 1.5 * r50]], circle_materials=MATERIAL_DARK, circle_heights=2.0)
    m_near, n_near = miss_rate(near)
    m_far, n_far = miss_rate(far)
    assert m_near / n_near < 0.01 < 0.5 < m_far / n_far
    # a flat dark wall at 0.7 r50: oblique beams are lost more often than head-on ones
    wall = World(walls=[[0.7 * r50, -50, 0.7 * r50, 50]], wall_materials=MATERIAL_DARK)
    a = np.asarray(EXACT.angles)
    a = np.where(a > math.pi, a - 2 * math.pi, a)
    head_on = miss_rate(wall, np.abs(a) < 0.2)
    oblique = miss_rate(wall, (np.abs(a) > 0.9) & (np.abs(a) < 1.1))
    assert head_on[0] / head_on[1] + 0.2 < oblique[0] / oblique[1]
    # a white wall at the same place is always seen
    white = World(walls=[[0.7 * r50, -50, 0.7 * r50, 50]], wall_materials=MATERIAL_WALL)
    assert miss_rate(white, np.abs(a) < 1.2)[0] == 0


def test_mixed_pixels_fall_between_foreground_and_background() -> None:
    # a person (seen like furniture) 1 m ahead, a wall 4 m behind
    w = World(
        walls=[[4.0, -8.0, 4.0, 8.0]],
        circles=[[1.0, 0.0, 0.25]],
        circle_materials=MATERIAL_PERSON,
        circle_heights=1.7,
    )
    a = np.asarray(EXACT.angles)
    a = np.where(a > math.pi, a - 2 * math.pi, a)
    front = np.abs(a) < 0.6
    clean = SimulatedLidar(EXACT, LidarFaults(), 0).scan(w, [0, 0, 0]).ranges
    person = clean < 1.0
    assert person.sum() >= 30  # the person is seen like furniture
    mid = (clean[front] > 1.0) & (clean[front] < 3.9)
    assert not mid.any()
    lidar = SimulatedLidar(EXACT, LidarFaults(mixed_pixel_prob=1.0), 0)
    for _ in range(10):
        r = lidar.scan(w, [0, 0, 0]).ranges
        between = (r > 1.0) & (r < 3.99) & front
        assert between.sum() == 2  # one per depth edge
        changed = r != clean
        assert changed.sum() == 2
    lidar = SimulatedLidar(EXACT, LidarFaults(mixed_pixel_prob=0.3), 1)
    n_mixed = sum(
        int(((r > 1.0) & (r < 3.99) & front).sum())
        for r in (lidar.scan(w, [0, 0, 0]).ranges for _ in range(200))
    )
    assert _inside(0.3, 0.3, n_mixed, 400)


def test_motion_skew_turns_the_scan_by_the_expected_angle() -> None:
    faults = LidarFaults(motion_skew=True)
    lidar = SimulatedLidar(EXACT, faults, 0)
    pose = np.array([0.3, -0.4, 0.2])
    w = 1.0  # rad/s: the last beam is cast 0.1 rad later than the first
    skewed = lidar.scan(SQUARE, pose, twist=(0.0, w), stamp=5.0)
    assert skewed.stamp == 5.0
    assert skewed.time_increment == pytest.approx(0.1 / EXACT.n_beams)
    static = lidar.scan(SQUARE, pose)
    assert np.array_equal(static.ranges, lidar.scan(SQUARE, pose, twist=(0.0, 0.0)).ranges)
    assert not np.array_equal(static.ranges, skewed.ranges)
    n = EXACT.n_beams
    for lo in (100, 300, 500, 740):  # blocks of 40 beams (5 ms): the block's mean delay
        hi = lo + 40
        t_mid = (lo + hi - 1) / 2 * skewed.time_increment
        deltas = np.arange(-0.01, 0.13, 0.0005)
        errs = [
            np.mean(
                (
                    simulate_scan(
                        SQUARE, pose + np.array([0.0, 0.0, d]), EXACT, noise=False
                    ).ranges[lo:hi]
                    - skewed.ranges[lo:hi]
                )
                ** 2
            )
            for d in deltas
        ]
        assert deltas[int(np.argmin(errs))] == pytest.approx(w * t_mid, abs=0.0015)
    # driving forward: the walls ahead come nearer during the revolution
    fwd = lidar.scan(SQUARE, [0, 0, 0], twist=(0.5, 0.0))
    poses = beam_poses([0, 0, 0], (0.5, 0.0), np.arange(n) * fwd.time_increment)
    assert poses[-1, 0] == pytest.approx(0.05, rel=0.01)
    assert fwd.ranges[0] == pytest.approx(2.0)
    back = n // 2  # looking backwards: the wall behind recedes by up to 5 cm
    assert fwd.ranges[back] == pytest.approx(2.0 + poses[back, 0], abs=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"dropout_rate": 1.0}, r"LidarFaults\.dropout_rate"),
        ({"angle_jitter_bins": -0.1}, r"LidarFaults\.angle_jitter_bins"),
        ({"range_bias_std": math.nan}, r"LidarFaults\.range_bias_std"),
        ({"glass_reflect_angle": 2.0}, r"LidarFaults\.glass_reflect_angle"),
        ({"glass_no_return_prob": 1.5}, r"LidarFaults\.glass_no_return_prob"),
        ({"dark_range_fraction": 0.0}, r"LidarFaults\.dark_range_fraction"),
        ({"dark_spread": 0.0}, r"LidarFaults\.dark_spread"),
        ({"motion_skew": 1}, r"LidarFaults\.motion_skew"),
    ],
)
def test_bad_faults_raise(kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        LidarFaults(**kwargs)


def test_bad_arguments_raise() -> None:
    with pytest.raises(ConfigurationError, match="preset: expected a LidarPreset"):
        SimulatedLidar("lds01", None, 0)  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="v"):
        SimulatedLidar(LDS01, None, 0).scan(SQUARE, [0, 0, 0], twist=(math.inf, 0.0))
