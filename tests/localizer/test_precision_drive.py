"""A claim withheld for the map's scale error alone: the gate says so, and the localizer asks
the driver to go towards the map's middle along a route through free space."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from symloc.bench.episode import drive_command
from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.grid.fields import surface_distance_field
from symloc.localizer.centering import CenteringConfig
from symloc.localizer.claim import ClaimConfig, ClaimGate, Verdict
from symloc.localizer.config import LocalizerConfig
from symloc.localizer.precision_route import FreeRoute
from symloc.localizer.types import Request, RequestKind, Status
from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import rectangle_room

RES = 0.05
ALPHAS = (0.05, 0.05, 0.05, 0.05)


@pytest.fixture(scope="module")
def long_room():  # type: ignore[no-untyped-def]
    """A 12 m x 3 m room: 5 m from its middle a 2 % scale error alone is 10 cm."""
    room = rectangle_room(12.0, 3.0)
    grid = world_to_grid(room.world, RES, free_seeds=room.center[None, :])
    return room, grid


def _claim(room, grid, truth, scale_std):  # type: ignore[no-untyped-def]
    gate = ClaimGate(
        surface_distance_field(grid),
        ALPHAS,
        ClaimConfig(map_scale_std=scale_std),
        scale_centre=room.center,
    )
    gate.anchor(truth, np.diag([0.03**2, 0.03**2, math.radians(1.0) ** 2]), np.zeros(3))
    return gate, gate.check(np.zeros(3), simulate_scan(room.world, truth, RPLIDAR_A2, 0))


def test_far_from_the_middle_the_scale_error_alone_withholds_the_claim(long_room) -> None:  # type: ignore[no-untyped-def]
    room, grid = long_room
    far = np.array([room.center[0] + 5.0, room.center[1], 0.3])
    gate, claim = _claim(room, grid, far, 0.02)
    assert claim.verdict is Verdict.WITHHELD, claim.reason
    assert claim.imprecise, claim.reason
    assert gate.middle_bound(claim)
    # the same pose on a map of known scale is claimed: nothing else held it back
    _, exact = _claim(room, grid, far, 0.0)
    assert exact.ok, exact.reason
    assert not gate.middle_bound(exact)
    # near the middle the same scale error is no obstacle
    _, near = _claim(room, grid, np.array([*room.center, 0.3]), 0.02)
    assert near.ok, near.reason


def test_a_claim_withheld_for_its_fit_is_not_middle_bound(long_room) -> None:  # type: ignore[no-untyped-def]
    room, grid = long_room
    truth = np.array([room.center[0] + 5.0, room.center[1], 0.3])
    gate, _ = _claim(room, grid, truth, 0.02)
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 1)
    ranges = np.array(scan.ranges, copy=True)
    ranges[: int(0.45 * ranges.size)] *= 0.6  # a crowd in front of half of the walls
    partly = gate.check(np.zeros(3), scan.with_ranges(ranges))
    assert partly.verdict is not Verdict.CLAIM
    assert not partly.imprecise, partly.reason
    assert not gate.middle_bound(partly)


def test_on_a_round_map_the_heading_alone_far_from_the_centre_is_middle_bound() -> None:
    """In a round room the camera's heading costs r times as much in position: 2.5 m from
    the centre a 0.6 deg heading std is 2.6 cm along the wall, too much to claim, at the
    centre nothing; the gate says the distance from the middle holds it back."""
    from symloc.sim.rooms import build_room

    room = build_room("circle", 3.0, lab=False)
    grid = world_to_grid(room.world, RES, free_seeds=room.center[None, :])
    centre = np.asarray(room.center, dtype=np.float64)
    cfg = ClaimConfig(map_rotation_std=math.radians(0.25))
    prior_cov = np.diag([0.03**2, 0.03**2, math.radians(0.6) ** 2])

    def claim_at(radius: float, heading_std: float):  # type: ignore[no-untyped-def]
        truth = np.array([centre[0] + radius, centre[1], 1.0])
        gate = ClaimGate(surface_distance_field(grid), ALPHAS, cfg, rotation_centre=centre)
        cov = prior_cov.copy()
        cov[2, 2] = math.radians(heading_std) ** 2
        scan = simulate_scan(room.world, truth, RPLIDAR_A2, 0)
        return gate, gate.confirm(truth, cov, scan)

    gate, far = claim_at(2.5, 0.6)
    assert far.verdict is Verdict.WITHHELD, far.reason
    assert far.imprecise, far.reason
    assert gate.middle_bound(far)
    _, near = claim_at(0.3, 0.6)
    assert near.ok, near.reason
    # a heading too unsure even at the centre (5 deg against the gate's 1.25): no drive
    gate, lost = claim_at(2.5, 5.0)
    assert lost.verdict is Verdict.WITHHELD
    assert not gate.middle_bound(lost)


def test_the_precise_place_is_clear_of_walls_and_nearest_the_middle(long_room) -> None:  # type: ignore[no-untyped-def]
    room, grid = long_room
    gate, _ = _claim(room, grid, np.array([*room.center, 0.0]), 0.02)
    place = gate.precise_place(0.4)
    assert place is not None
    np.testing.assert_allclose(place, room.center, atol=2 * RES)
    assert gate.precise_place(5.0) is None  # no free cell of a 3 m wide room is 5 m clear


def _u_room() -> OccupancyGrid:
    """A U: two 1.5 m wide arms (x 0-1.5 and 3.5-5 m) joined by a base (y 0-1.5 m); a wall
    fills the notch between the arms (x 1.5-3.5 m, y 1.5-6 m)."""
    n = int(6 / RES)
    data = np.full((n + 2, int(5 / RES) + 2), 100, dtype=np.int8)
    data[1:-1, 1:-1] = 0
    notch_x = slice(int(1.5 / RES) + 1, int(3.5 / RES) + 1)
    data[int(1.5 / RES) + 1 : -1, notch_x] = 100
    return OccupancyGrid(data, RES, np.array([-RES, -RES, 0.0]))


def _occupied_at(grid: OccupancyGrid, points: np.ndarray) -> np.ndarray:
    cells = grid.world_to_cell(points)
    return grid.data[cells[:, 0], cells[:, 1]] > 50


def test_the_route_goes_round_the_wall_a_straight_line_would_cross() -> None:
    grid = _u_room()
    field = surface_distance_field(grid)
    start, goal = np.array([0.75, 5.0]), np.array([4.25, 5.0])  # the tips of the two arms
    line = start + np.linspace(0.0, 1.0, 50)[:, None] * (goal - start)
    assert _occupied_at(grid, line).any()  # straight there: through the notch's wall
    route = FreeRoute(field, goal, clearance=0.4)
    here, path = start.copy(), [start.copy()]
    for _ in range(60):
        target = route.waypoint(here, 0.5)
        assert target is not None
        step = target - here
        if np.hypot(*step) < 1e-9:
            break
        here = here + step * min(1.0, 0.25 / float(np.hypot(*step)))
        path.append(here.copy())
    assert np.hypot(*(here - goal)) < 2 * RES
    pts = np.array(path)
    dense = np.concatenate(
        [a + np.linspace(0, 1, 10)[:, None] * (b - a) for a, b in itertools.pairwise(pts)]
    )
    assert not _occupied_at(grid, dense).any()
    assert pts[:, 1].min() < 1.5  # it went down the arm and through the base


def test_no_route_from_a_place_cut_off_from_the_goal() -> None:
    data = np.zeros((40, 80), dtype=np.int8)
    data[:, 40] = 100  # a wall from side to side: two rooms
    grid = OccupancyGrid(data, RES, np.zeros(3))
    route = FreeRoute(surface_distance_field(grid), np.array([3.0, 1.0]), clearance=0.2)
    assert route.waypoint(np.array([3.5, 1.0])) is not None
    assert route.waypoint(np.array([1.0, 1.0])) is None


def test_go_to_needs_a_target_and_is_driven_at_travelling_speed() -> None:
    with pytest.raises(ConfigurationError, match="GO_TO needs a"):
        Request(RequestKind.GO_TO)
    scan = simulate_scan(rectangle_room(12.0, 3.0).world, np.zeros(3), RPLIDAR_A2, 0)
    target = np.array([3.0, 0.0])
    slow = drive_command(
        Status.LOST, Request(RequestKind.GO_TO_CENTRE, target=target), scan, CenteringConfig()
    )
    fast = drive_command(
        Status.LOST, Request(RequestKind.GO_TO, target=target), scan, CenteringConfig()
    )
    assert slow[0] == pytest.approx(CenteringConfig().max_linear_speed)
    assert fast[0] == pytest.approx(0.3)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("precision_drive", "yes"),
        ("precision_clearance", 0.0),
        ("precision_clearance", -0.4),
        ("precision_lookahead", float("nan")),
    ],
)
def test_bad_precision_settings_are_refused_by_name(field: str, value: object) -> None:
    with pytest.raises(ConfigurationError, match=f"LocalizerConfig.{field}"):
        LocalizerConfig(**{field: value})
