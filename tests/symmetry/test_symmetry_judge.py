from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.geometry import transform_points
from symloc.scan import LaserScan
from symloc.sim.lidar import LDS01, PAPER_15M, RPLIDAR_A2, simulate_scan
from symloc.sim.rooms import add_furniture, build_room, hallway, rectangle_room
from symloc.sim.world import World, polygon_walls
from symloc.symmetry import SymmetryConfig, judge_symmetry
from symloc.symmetry.order import SymmetryOrder

CFG = SymmetryConfig.from_lidar(PAPER_15M)


def scan_in(world: World, pose: list[float], seed: int = 0, preset=PAPER_15M) -> LaserScan:
    return simulate_scan(world, np.asarray(pose, dtype=float), preset, seed)


def world_center(report, pose) -> np.ndarray:
    return transform_points(np.asarray(pose, dtype=float), report.center[None])[0]


@pytest.mark.parametrize(
    ("name", "n"), [("triangle", 3), ("square", 4), ("pentagon", 5), ("hexagon", 6), ("octagon", 8)]
)
def test_regular_polygons_off_centre(name: str, n: int) -> None:
    room = build_room(name, 4.0, lab=False)
    pose = [0.9, -0.6, 0.4]
    rep = judge_symmetry(scan_in(room.world, pose), config=CFG)
    assert rep.kind == "polygon"
    assert rep.symmetric
    assert rep.regular
    assert rep.order == SymmetryOrder.finite(n)
    assert rep.n_corners == n
    assert rep.gv_distance == pytest.approx(4.0, abs=0.02)
    assert np.hypot(*(world_center(rep, pose) - room.center)) < 0.01
    assert "maps them onto each other" in rep.reason


def test_circle_order_is_infinite_and_centre_is_accurate() -> None:
    room = build_room("circle", 5.0, lab=False)
    pose = [2.0, 1.5, -2.0]
    rep = judge_symmetry(scan_in(room.world, pose), config=CFG)
    assert rep.kind == "circle"
    assert rep.continuous
    assert rep.order == SymmetryOrder.CIRCLE
    assert rep.order.is_circle
    assert rep.regular
    assert rep.symmetric
    assert rep.gv_distance == pytest.approx(5.0, abs=0.01)
    assert np.hypot(*(world_center(rep, pose) - room.center)) < 0.01
    assert rep.to_dict()["order"] == "inf"


def test_rectangle_is_order_two_not_a_square() -> None:
    room = rectangle_room(6.0, 5.0)
    pose = [1.0, 0.7, 1.0]
    rep = judge_symmetry(scan_in(room.world, pose), config=CFG)
    assert rep.kind == "rectangle"
    assert rep.order == SymmetryOrder.finite(2)
    assert rep.symmetric
    assert not rep.regular
    assert rep.gv_distance == pytest.approx(math.hypot(3.0, 2.5), abs=0.02)
    assert np.hypot(*(world_center(rep, pose) - room.center)) < 0.01


def test_rhombus_is_order_two_polygon() -> None:
    a = math.radians(70)
    v = np.array(
        [[0, 0], [5, 0], [5 + 5 * math.cos(a), 5 * math.sin(a)], [5 * math.cos(a), 5 * math.sin(a)]]
    )
    v = v - v.mean(axis=0)
    rep = judge_symmetry(scan_in(World(polygon_walls(v)), [0.5, 0.3, 0.0]), config=CFG)
    assert rep.kind == "polygon"
    assert rep.order == SymmetryOrder.finite(2)
    assert not rep.regular


def test_kite_is_asymmetric_with_reason() -> None:
    v = np.array([[0.0, -4.0], [3.0, 0.0], [0.0, 2.5], [-3.0, 0.0]])
    rep = judge_symmetry(scan_in(World(polygon_walls(v)), [0.2, -0.5, 0.3]), config=CFG)
    assert rep.kind == "asymmetric"
    assert not rep.symmetric
    assert rep.order == SymmetryOrder.finite(1)
    assert "no rotation" in rep.reason
    assert np.all(np.isnan(rep.center))


def test_hallway_with_unseen_ends() -> None:
    room = hallway(12.0, 2.0)
    pose = [1.0, 0.3, 0.2]
    rep = judge_symmetry(
        scan_in(room.world, pose, preset=LDS01), config=SymmetryConfig.from_lidar(LDS01)
    )
    assert rep.kind == "hallway"
    assert rep.order == SymmetryOrder.finite(2)
    assert rep.symmetric
    assert "ends unseen" in rep.reason
    assert "undetermined" in rep.reason
    # the centre lies on the mid-line: its world y is the hallway's axis y = 0
    assert abs(world_center(rep, pose)[1]) < 0.05
    assert math.isnan(rep.gv_distance)
    # the axis is along world x
    axis_world = rep.axis_angle + pose[2]
    assert abs(math.sin(axis_world)) < 0.05


def test_closed_hallway_seen_whole_is_a_rectangle() -> None:
    room = hallway(12.0, 2.0)
    rep = judge_symmetry(scan_in(room.world, [1.0, 0.3, 0.2]), config=CFG)
    assert rep.kind == "rectangle"
    assert rep.order == SymmetryOrder.finite(2)


def test_open_door_breaks_symmetry() -> None:
    room = build_room("square", 4.0, lab=False, door=True)
    rep = judge_symmetry(scan_in(room.world, [0.5, 0.5, 0.0]), config=CFG)
    assert rep.kind == "asymmetric"
    assert not rep.symmetric
    assert "opening" in rep.reason


def test_box_inside_breaks_symmetry() -> None:
    room = add_furniture(build_room("square", 4.0, lab=False), boxes=1, rng=3)
    rep = judge_symmetry(scan_in(room.world, [0.1, 0.1, 0.0]), config=CFG)
    assert not rep.symmetric
    assert rep.kind == "asymmetric"


def test_l_shaped_room_is_not_symmetric() -> None:
    room = build_room("l_shaped", 5.0, lab=False)
    for p in room.positions_inside(6):
        rep = judge_symmetry(scan_in(room.world, [p[0], p[1], 0.0]), config=CFG)
        assert not rep.symmetric, rep.reason


def test_mean_centroid_fails_off_centre_and_says_why() -> None:
    room = build_room("square", 4.0, lab=False)
    rep = judge_symmetry(scan_in(room.world, [1.5, 1.0, 0.0]), config=CFG, centroid="mean")
    assert not rep.symmetric
    assert "mean centroid" in rep.reason
    assert "would be order 4" in rep.reason


def test_beyond_range_is_unknown() -> None:
    room = build_room("square", 7.0, lab=False)
    rep = judge_symmetry(
        scan_in(room.world, [0.0, 0.0, 0.0], preset=LDS01), config=SymmetryConfig.from_lidar(LDS01)
    )
    assert rep.kind == "unknown"
    assert rep.order is None  # unknown: no order, not a circle
    assert rep.to_dict()["order"] == 0  # the JSON form kept
    assert "no return" in rep.reason


def test_dropouts_are_bridged() -> None:
    room = build_room("hexagon", 4.0, lab=False)
    scan = simulate_scan(
        room.world, np.array([0.5, 0.2, 0.0]), RPLIDAR_A2.with_(dropout_rate=0.08), 5
    )
    assert np.isnan(scan.ranges).any()
    rep = judge_symmetry(scan, config=SymmetryConfig.from_lidar(RPLIDAR_A2))
    assert rep.kind == "polygon"
    assert rep.order == SymmetryOrder.finite(6)


def _scan(ranges, inc=2 * math.pi / 360) -> LaserScan:
    return LaserScan(0.0, inc, 0.1, 10.0, np.asarray(ranges, dtype=float))


@pytest.mark.parametrize(
    ("ranges", "match"),
    [
        ([1.0], "too few points"),
        (np.full(360, np.nan), "too few points: 0 valid of 360 beams"),
        (np.full(360, np.inf), "360 no return"),
        (np.r_[np.ones(5), np.full(355, np.nan)], "too few points: 5 valid"),
    ],
)
def test_bad_scans_are_unknown_with_reason(ranges, match: str) -> None:
    rep = judge_symmetry(_scan(ranges))
    assert rep.kind == "unknown"
    assert not rep.symmetric
    assert rep.order is None  # unknown: no order, not a circle
    assert rep.to_dict()["order"] == 0  # the JSON form kept
    assert match in rep.reason


def test_partial_field_of_view_is_unknown() -> None:
    scan = LaserScan(-math.pi * 0.75, math.radians(1.0), 0.1, 10.0, np.full(271, 2.0))
    rep = judge_symmetry(scan)
    assert rep.kind == "unknown"
    assert "field of view" in rep.reason


def test_judge_rejects_bad_arguments() -> None:
    scan = _scan(np.full(360, 2.0))
    with pytest.raises(ConfigurationError, match="centroid: expected one of"):
        judge_symmetry(scan, centroid="median")
    with pytest.raises(ConfigurationError, match="scan: expected a LaserScan"):
        judge_symmetry(np.ones(360))  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="config: expected a SymmetryConfig"):
        judge_symmetry(scan, config={"k_sigma": 3})  # type: ignore[arg-type]


def test_exact_circle_scan_by_hand() -> None:
    # a robot at the centre of a 3 m round room, no noise: every range is 3
    rep = judge_symmetry(_scan(np.full(360, 3.0)))
    assert rep.kind == "circle"
    np.testing.assert_allclose(rep.center, [0.0, 0.0], atol=1e-9)
    assert rep.gv_distance == pytest.approx(3.0)


ROOMS = {
    name: build_room(name, 4.0, lab=False) for name in ("triangle", "square", "hexagon", "circle")
}


@settings(max_examples=20, deadline=None)
@given(
    name=st.sampled_from(sorted(ROOMS)),
    which=st.integers(0, 11),
    heading=st.floats(-math.pi, math.pi),
    seed=st.integers(0, 2**16),
)
def test_rotating_the_robot_does_not_change_the_verdict(
    name: str, which: int, heading: float, seed: int
) -> None:
    room = ROOMS[name]
    p = room.positions_inside(12)[which]
    a = judge_symmetry(scan_in(room.world, [p[0], p[1], 0.0], seed), config=CFG)
    b = judge_symmetry(scan_in(room.world, [p[0], p[1], heading], seed + 1), config=CFG)
    assert (a.kind, a.order, a.symmetric) == (b.kind, b.order, b.symmetric)
    assert a.symmetric
    # the centre is the same point of the world
    np.testing.assert_allclose(
        world_center(a, [p[0], p[1], 0.0]), world_center(b, [p[0], p[1], heading]), atol=0.01
    )


@settings(max_examples=15, deadline=None)
@given(name=st.sampled_from(sorted(ROOMS)), box_seed=st.integers(0, 1000), which=st.integers(0, 7))
def test_adding_a_box_breaks_the_symmetry(name: str, box_seed: int, which: int) -> None:
    room = add_furniture(ROOMS[name], boxes=1, rng=box_seed)
    p = room.positions_inside(8)[which]
    rep = judge_symmetry(scan_in(room.world, [p[0], p[1], 0.3], box_seed), config=CFG)
    assert not rep.symmetric, rep.reason


@settings(max_examples=60, deadline=None)
@given(
    ranges=st.lists(
        st.one_of(
            st.floats(0.0, 20.0),
            st.sampled_from([math.nan, math.inf, -math.inf, 0.05]),
        ),
        min_size=1,
        max_size=400,
    ),
    full=st.booleans(),
)
def test_judge_never_raises_on_arbitrary_ranges(ranges: list[float], full: bool) -> None:
    n = len(ranges)
    inc = 2 * math.pi / n if full else math.radians(0.5)
    rep = judge_symmetry(LaserScan(0.0, inc, 0.1, 15.0, np.asarray(ranges)))
    assert rep.kind in ("polygon", "circle", "rectangle", "hallway", "asymmetric", "unknown")
    assert rep.symmetric == (rep.order is not None and rep.order.symmetric)
    assert isinstance(rep.reason, str)
    assert rep.reason


@settings(max_examples=30, deadline=None)
@given(
    n=st.integers(12, 400),
    seed=st.integers(0, 2**16),
    spike=st.floats(0.0, 1.0),
)
def test_judge_never_raises_on_noisy_closed_scans(n: int, seed: int, spike: float) -> None:
    rng = np.random.default_rng(seed)
    ranges = rng.uniform(0.5, 8.0) + rng.normal(0, spike, n).cumsum() * 0.1
    ranges = np.abs(ranges) + 0.2
    rep = judge_symmetry(LaserScan(0.0, 2 * math.pi / n, 0.1, 15.0, ranges))
    assert rep.kind in ("polygon", "circle", "rectangle", "hallway", "asymmetric", "unknown")
