"""Scan-to-map alignment: it finds the pose, knows what it cannot see, and says when it misfits."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.grid.fields import distance_field, surface_distance_field
from symloc.mcl.beams import select_beams
from symloc.mcl.motion_model import Odometer, carry_by_odometry
from symloc.mcl.scan_to_map import ScanMatchConfig, match_scan_to_map, scan_points
from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import hallway, l_shaped_room, regular_polygon_room


def _points(world, pose, preset=RPLIDAR_A2, seed=0):
    scan = simulate_scan(world, pose, preset, seed)
    b = select_beams(scan, len(scan))
    return scan_points(b.ranges[b.hit], b.angles[b.hit], (0.0, 0.0, 0.0))


@pytest.fixture(scope="module")
def l_room():
    room = l_shaped_room(4.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    return room, surface_distance_field(grid)


def test_recovers_the_pose_from_a_perturbed_start(l_room) -> None:
    room, field = l_room
    rng = np.random.default_rng(3)
    for _ in range(10):
        truth = np.array(
            [*room.positions_inside(30, margin=0.4)[rng.integers(30)], rng.uniform(-3, 3)]
        )
        init = truth + np.array(
            [rng.normal(0, 0.08), rng.normal(0, 0.08), math.radians(rng.normal(0, 4))]
        )
        m = match_scan_to_map(field, _points(room.world, truth, seed=int(rng.integers(99))), init)
        assert math.hypot(*(m.pose[:2] - truth[:2])) < 0.02  # half a 5 cm cell
        assert abs(math.remainder(m.pose[2] - truth[2], 2 * math.pi)) < math.radians(1.0)
        assert m.inlier_fraction > 0.97
        sx, sy, sth = np.sqrt(np.diag(m.covariance))
        assert max(sx, sy) < 0.03
        assert sth < math.radians(1.0)


def test_a_corridor_leaves_its_axis_unconstrained() -> None:
    room = hallway(30.0, 2.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    field = surface_distance_field(grid)
    short = RPLIDAR_A2.with_(range_max=6.0)  # the ends are out of range
    truth = np.array([1.0, 0.2, 0.1])
    m = match_scan_to_map(
        field, _points(room.world, truth, short), truth + np.array([0.3, 0.05, 0.02])
    )
    cov = m.covariance
    assert math.sqrt(cov[0, 0]) > 0.2  # along the corridor: ten times the claim gate's limit
    assert math.sqrt(cov[1, 1]) < 0.02  # across it: the walls
    assert abs(m.pose[1] - truth[1]) < 0.02
    # a prior along the axis bounds what the scan cannot
    prior = np.diag([0.1**2, 0.1**2, math.radians(3) ** 2])
    m2 = match_scan_to_map(
        field,
        _points(room.world, truth, short),
        truth + np.array([0.05, 0.0, 0.0]),
        prior=(truth, prior),
    )
    assert math.sqrt(m2.covariance[0, 0]) == pytest.approx(0.1, rel=0.05)


def test_a_scan_from_elsewhere_does_not_fit(l_room) -> None:
    room, field = l_room
    here = np.array([-0.8, -0.8, 0.3])
    elsewhere = np.array([0.9, -1.0, 2.0])
    m = match_scan_to_map(field, _points(room.world, elsewhere), here)
    assert m.inlier_fraction < 0.5


def test_surface_field_is_zero_on_the_wall_centre_line() -> None:
    room = l_shaped_room(4.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    surf = surface_distance_field(grid)
    plain = distance_field(grid, 1.0)
    mids = 0.5 * (room.boundary + np.roll(room.boundary, -1, axis=0))
    assert np.all(surf.lookup(mids) <= 0.05)
    assert np.all(plain.lookup(mids) <= 0.05)
    inside = room.positions_inside(20, margin=0.5)
    assert np.all(surf.lookup(inside) > 0.3)


def test_settings_are_validated() -> None:
    with pytest.raises(ConfigurationError, match="information_scale"):
        ScanMatchConfig(information_scale=0.0)
    with pytest.raises(ConfigurationError, match="iterations"):
        ScanMatchConfig(iterations=0)
    grid = world_to_grid(l_shaped_room(4.0).world, 0.05)
    with pytest.raises(ConfigurationError, match="outlier_distance"):
        match_scan_to_map(surface_distance_field(grid, 0.2), np.zeros((5, 2)), np.zeros(3))
    with pytest.raises(ConfigurationError, match="initial"):
        match_scan_to_map(surface_distance_field(grid), np.zeros((5, 2)), [np.nan, 0, 0])


def test_carry_by_odometry_composes_exactly_and_grows_the_covariance() -> None:
    pose = np.array([1.0, 2.0, 0.5])
    cov = np.diag([1e-4, 1e-4, 1e-4])
    odom0 = np.array([5.0, -1.0, 1.0])
    odom1 = np.array([5.0 + 0.5 * math.cos(1.0), -1.0 + 0.5 * math.sin(1.0), 1.3])
    out, c = carry_by_odometry(pose, cov, odom0, odom1, (0.05, 0.05, 0.05, 0.05))
    assert out == pytest.approx([1.0 + 0.5 * math.cos(0.5), 2.0 + 0.5 * math.sin(0.5), 0.8])
    assert np.all(np.linalg.eigvalsh(c - cov) >= -1e-12)  # never shrinks
    assert c[2, 2] > cov[2, 2]
    same, c0 = carry_by_odometry(pose, cov, odom0, odom0, (0.05, 0.05, 0.05, 0.05))
    assert same == pytest.approx(pose)
    assert c0 == pytest.approx(cov)
    # a heading uncertainty spreads the position of a robot that drives on
    _, c_far = carry_by_odometry(
        np.zeros(3), np.diag([0, 0, 0.01]), np.zeros(3), np.array([2.0, 0.0, 0.0]), (0, 0, 0, 0)
    )
    assert math.sqrt(c_far[1, 1]) == pytest.approx(2.0 * 0.1, rel=0.05)


def test_carry_by_odometry_grows_with_the_path_and_turning_travelled() -> None:
    odo = Odometer()
    # out 1 m along x, turn round in place, back 1 m: net increment zero
    path = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.5], [1.0, 0.0, 3.0]]
    path += [[1.0, 0.0, math.pi], [0.5, 0.0, math.pi], [0.0, 0.0, math.pi]]
    for p in path:
        travelled = odo.advance(np.array(p))
    assert travelled == pytest.approx((2.0, math.pi))
    assert odo.advance(np.array(path[-1])) == pytest.approx((2.0, math.pi))  # no step, no motion
    assert odo.since((1.0, 0.0)) == pytest.approx((1.0, math.pi))
    alphas = (0.01, 0.01, 0.01, 0.01)
    cov = np.diag([1e-4, 1e-4, 1e-4])
    start, end = np.array(path[0]), np.array(path[-1])
    net_pose, net_cov = carry_by_odometry(np.zeros(3), cov, start, end, alphas)
    pose, grown = carry_by_odometry(np.zeros(3), cov, start, end, alphas, travelled=travelled)
    assert pose == pytest.approx(net_pose)  # the mean is the odometry's, path or not
    assert np.all(np.linalg.eigvalsh(grown - net_cov) >= -1e-12)  # never less
    assert grown[2, 2] >= cov[2, 2] + 0.01 * math.pi**2 - 1e-12  # every turn's error
    assert grown[0, 0] + grown[1, 1] >= 2 * 1e-4 + 0.01 * 2.0**2 - 1e-12  # every metre's
    # one step: the path is the increment, and the covariance is the model's own
    step = np.array([0.5, 0.1, 0.3])
    one = Odometer()
    one.advance(np.zeros(3))
    same = carry_by_odometry(
        np.zeros(3), cov, np.zeros(3), step, alphas, travelled=one.advance(step)
    )
    assert same[1] == pytest.approx(
        carry_by_odometry(np.zeros(3), cov, np.zeros(3), step, alphas)[1]
    )


def test_a_round_room_leaves_the_rotation_about_its_centre_unconstrained() -> None:
    from symloc.sim.rooms import circular_room

    room = circular_room(2.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    field = surface_distance_field(grid)
    truth = np.array([0.6, -0.3, 0.4])
    m = match_scan_to_map(field, _points(room.world, truth), truth)
    # the rasterised circle ripples, but a 5-degree turn about the centre costs nothing
    assert math.degrees(math.sqrt(m.covariance[2, 2])) > 2.0  # twice the claim gate's limit
    _, v = np.linalg.eigh(m.information)
    weakest = v[:, 0] / v[2, 0]  # per radian of heading
    assert weakest[:2] == pytest.approx([-(truth[1] - 0.0), truth[0] - 0.0], abs=0.1)
    # distance from the centre is known
    radial = truth[:2] / np.hypot(*truth[:2])
    assert math.sqrt(radial @ m.covariance[:2, :2] @ radial) < 0.02


def test_numpy_lookups_give_the_compiled_match_bit_for_bit(l_room) -> None:
    """``compiled=False`` (SLAM's map error, a process without numba) runs the kernels'
    expressions in NumPy: the same match, to the last bit."""
    room, field = l_room
    rng = np.random.default_rng(5)
    for _ in range(5):
        truth = np.array([*room.positions_inside(30, margin=0.4)[rng.integers(30)], 0.3])
        init = truth + np.array([0.06, -0.04, math.radians(3.0)])
        pts = _points(room.world, truth, seed=int(rng.integers(99)))
        a = match_scan_to_map(field, pts, init)
        b = match_scan_to_map(field, pts, init, ScanMatchConfig(compiled=False))
        assert np.array_equal(a.pose, b.pose)
        assert np.array_equal(a.information, b.information)
        assert np.array_equal(a.covariance, b.covariance)
        assert (a.inlier_fraction, a.iterations) == (b.inlier_fraction, b.iterations)


WALLS = ScanMatchConfig(wall_std=0.01, wall_tilt_std=math.radians(1.0))


def test_a_square_rooms_scan_is_four_walls() -> None:
    from symloc.mcl.scan_to_map import _inliers, _walls
    from symloc.sim.rooms import regular_polygon_room

    room = regular_polygon_room(4, 2.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    field = surface_distance_field(grid)
    pose = np.array([*room.center, 0.3])
    pts = _inliers(field, _points(room.world, pose)[::4], pose, WALLS)
    walls = _walls(field, pts, pose, WALLS)
    sizes = np.bincount(walls.label)
    assert np.count_nonzero(sizes >= 5) == 4
    assert sizes[sizes >= 5].sum() >= 0.9 * len(pts)  # corners aside, every point on a wall
    # the big walls' normals are the square's: two pairs, a quarter turn apart
    big = walls.normal[sizes >= 5]
    angles = np.arctan2(big[:, 1], big[:, 0])
    assert np.all(np.abs(np.angle(np.exp(4j * (angles - angles[0])))) < math.radians(20.0))


def test_a_walls_shared_error_is_counted_once() -> None:
    """Twice the beams on the same walls: the independent model's position std shrinks by
    sqrt(2); with the walls' shared error it hardly moves (it is the walls' own), while a
    corridor's few end-wall beams, which the independent model discounts tenfold, count
    nearly in full."""
    room = hallway(13.5, 2.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    field = surface_distance_field(grid)
    pose = np.array([*room.center, 0.1]) + np.array([0.0, 0.2, 0.0])
    pts = _points(room.world, pose)

    def across_along(cfg: ScanMatchConfig) -> tuple[float, float]:
        cov = match_scan_to_map(field, pts, pose, cfg).covariance
        return math.sqrt(cov[1, 1]), math.sqrt(cov[0, 0])

    few, many = across_along(ScanMatchConfig()), across_along(ScanMatchConfig(max_points=360))
    assert many[0] < 0.8 * few[0]
    few_w = across_along(WALLS)
    many_w = across_along(dataclasses.replace(WALLS, max_points=360))
    assert many_w[0] > 0.9 * few_w[0]
    # two long walls, each known to about wall_std
    assert 0.5 * WALLS.wall_std < few_w[0] < 2.0 * WALLS.wall_std
    # along the corridor: the end walls' beams
    assert few_w[1] < 0.6 * few[1]
    assert few_w[1] < 0.05


@pytest.mark.parametrize("cfg", [ScanMatchConfig(), WALLS], ids=["independent", "walls"])
@pytest.mark.parametrize("off", [0.1, -0.15])
def test_a_prior_pulls_the_pose_as_much_as_the_covariance_says(cfg, off) -> None:
    """With a prior, the pose is the Gaussian product of the scan's own match and the prior
    under the covariance the match reports. The alignment weighs the scan by
    ``information_scale``; the walls model reports up to tenfold more along a short
    corridor's axis (its end walls), and before the two were reconciled the pose went twice as
    far towards a wrong prior as its covariance admitted (heavy dev corridor_short#1: a claim
    12 cm off published with an along-axis std of 2.8 cm)."""
    room = hallway(6.0, 2.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    field = surface_distance_field(grid)
    pose = np.array([*room.center, 0.1]) + np.array([1.5, 0.2, 0.0])
    pts = _points(room.world, pose)
    alone = match_scan_to_map(field, pts, pose, cfg)
    mean = pose + np.array([off, 0.0, 0.0])
    prior_cov = np.diag([0.03**2, 0.03**2, math.radians(3) ** 2])
    fused = match_scan_to_map(field, pts, mean, cfg, prior=(mean, prior_cov))
    expected = alone.pose + fused.covariance @ np.linalg.solve(prior_cov, mean - alone.pose)
    assert abs(fused.pose[0] - alone.pose[0]) > 0.005  # the prior does pull
    assert np.allclose(fused.pose[:2], expected[:2], atol=0.002)
    assert abs(fused.pose[2] - expected[2]) < math.radians(0.1)


def test_the_walls_model_keeps_information_scales_heading() -> None:
    """The walls model sets the position's std; the heading is no surer than
    ``information_scale`` makes it (on dev the walls' heading let an unconverged match
    through), and the position block of the covariance is the walls model's own."""
    from symloc.mcl.scan_to_map import _covariance, _heading_floored

    room = regular_polygon_room(5, 3.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    field = surface_distance_field(grid)
    pose = np.array([*room.center, 0.2]) + np.array([0.4, -0.3, 0.0])
    pts = _points(room.world, pose)
    plain = match_scan_to_map(field, pts, pose).covariance
    walls = match_scan_to_map(field, pts, pose, WALLS).covariance
    assert walls[2, 2] == pytest.approx(plain[2, 2], rel=1e-6)
    assert walls[0, 0] + walls[1, 1] < plain[0, 0] + plain[1, 1]
    # the floor itself: position block kept, heading variance raised, correlation kept
    info = np.array([[400.0, 10.0, 30.0], [10.0, 300.0, -20.0], [30.0, -20.0, 9000.0]])
    floored = _heading_floored(info, info / 4.0)
    a, b = _covariance(info), _covariance(floored)
    assert np.allclose(a[:2, :2], b[:2, :2])
    assert b[2, 2] == pytest.approx(_covariance(info / 4.0)[2, 2])
    corr = a[0, 2] / math.sqrt(a[0, 0] * a[2, 2])
    assert b[0, 2] / math.sqrt(b[0, 0] * b[2, 2]) == pytest.approx(corr)
    # a heading surer under information_scale than under the walls stays the walls'
    assert np.array_equal(_heading_floored(info / 4.0, info), info / 4.0)


def test_wall_settings_are_validated() -> None:
    with pytest.raises(ConfigurationError, match="wall_std"):
        ScanMatchConfig(wall_std=-0.01)
    with pytest.raises(ConfigurationError, match="wall_gap"):
        ScanMatchConfig(wall_gap=0.0)
