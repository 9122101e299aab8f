"""The mapping trip's driver: around furniture, along a whole corridor, stopping to look
around where the lap did not pass (bench.exploration, bench.episode)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from symloc.bench.episode import RobotBody, drive_waypoints, look_around_at
from symloc.bench.exploration import _line_free, coverage_stops, exploration_path, free_route
from symloc.sim.generator import generate_world
from symloc.sim.regimes import get_regime
from symloc.sim.robot import DiffDriveRobot


@pytest.fixture(scope="module")
def corridor():
    """A 57 m corridor of the dev split with a 0.34 m box near (-4.7, 13.7)."""
    return generate_world("corridor_long", 0).build()


def test_route_goes_around_the_box_and_stays_clear(corridor):
    box = np.asarray(corridor.obstacles[0]).mean(axis=0)
    axis = np.array([-7.57 - 9.45, 27.8 + 27.22])
    axis /= np.hypot(*axis)
    a, b = box - 2.0 * axis, box + 2.0 * axis  # the straight line runs through the box
    clearance = 0.33
    free = corridor.free_space(clearance)
    assert not _line_free(free, a, b)
    via = free_route(corridor, clearance)(a, b)
    assert via.shape[0] >= 2  # a detour, not the straight line
    assert np.allclose(via[-1], b)
    legs = np.vstack([a[None], via])
    for p, q in itertools.pairwise(legs):
        t = np.linspace(0.0, 1.0, 200)[:, None]
        d = corridor.world.distance(p + t * (q - p))
        assert d.min() >= clearance - free.resolution


def test_route_is_empty_when_no_free_path_exists(corridor):
    route = free_route(corridor, 0.33)
    outside = np.array([100.0, 100.0])  # outside the room: snapped to its nearest free cell
    assert route(np.zeros(2), outside).shape[0] >= 1
    walled = free_route(corridor, 5.0)  # nothing is 5 m from a wall in a 2 m corridor
    assert walled(np.zeros(2), np.array([5.0, -13.0])).shape == (0, 2)


@pytest.mark.parametrize("seed", [0, 1])
def test_mapping_drive_covers_the_whole_corridor_past_the_box(corridor, seed):
    """With a realistic robot (wheel calibration error, actuation noise) the driver reaches every
    waypoint of the outline; driving straight at each one, it stopped at the box and left
    most of the corridor unmapped."""
    rng = np.random.default_rng(seed)
    config = get_regime("realistic").robot_config(rng)
    path = exploration_path(corridor, margin=0.5)
    start = np.array([-6.45, 20.83, 1.85])  # where the bench's mapping stage left the robot
    robot = RobotBody(DiffDriveRobot(start, config, rng, world=corridor.world, odom_origin=start))
    trace: list[np.ndarray] = []
    skipped = drive_waypoints(
        robot,
        path,
        laps=1.0,
        dt=0.2,
        on_step=trace.append,
        route=free_route(corridor, config.radius + 0.15),
    )
    assert skipped == 0
    along = (np.asarray(trace)[:, :2] - path[0]) @ (
        (path[1] - path[0]) / np.hypot(*(path[1] - path[0]))
    )
    length = float(np.hypot(*(path[1] - path[0])))
    assert along.min() < 0.05 * length
    assert along.max() > 0.95 * length


def _lap(room, margin=0.5, per_edge=20):
    """Points along the outline lap, ``per_edge`` per edge."""
    path = exploration_path(room, margin=margin)
    return np.vstack(
        [np.linspace(p, q, per_edge) for p, q in zip(path, np.roll(path, -1, axis=0), strict=True)]
    )


def test_coverage_stops_leave_no_reachable_place_farther_than_reach():
    """A large regular room: the lap along the walls leaves its middle metres from the trip;
    with the stops every free place the lap's component holds is within reach, each stop is
    free and off the lap, and they come nearest first."""
    room = generate_world("regular", 1).build()
    lap = _lap(room)
    clearance, reach = 0.33, 1.0
    free = room.free_space(clearance)
    rr, cc = np.nonzero(free.free & (free.labels == free.reachable_label))
    cells = free.origin + (np.column_stack([cc, rr]) + 0.5) * free.resolution
    far = np.min(np.hypot(*(cells[:, None, :] - lap[None, :, :]).transpose(2, 0, 1)), axis=1)
    assert far.max() > 2.0  # the lap alone leaves the middle far from the trip
    start = lap[-1]
    stops = coverage_stops(room, lap, reach=reach, clearance=clearance, start=start)
    assert 3 <= stops.shape[0] < 60
    trip = np.vstack([lap, stops])
    gap = np.min(np.hypot(*(cells[:, None, :] - trip[None, :, :]).transpose(2, 0, 1)), axis=1)
    assert gap.max() <= reach + free.resolution
    row, col = free.cells(stops)
    assert free.free[row, col].all()
    off = np.min(np.hypot(*(stops[:, None, :] - lap[None, :, :]).transpose(2, 0, 1)), axis=1)
    assert off.min() > reach
    hops = np.hypot(*(stops - np.vstack([start[None], stops[:-1]])).T)
    assert hops[0] <= np.hypot(*(stops - start).T).min() + 1e-9  # nearest first
    # a trip that already passed everywhere needs no stop; nothing driven, nothing to extend
    assert coverage_stops(room, cells, reach=reach, clearance=clearance).shape == (0, 2)
    assert coverage_stops(room, np.zeros((0, 2)), reach=reach, clearance=clearance).shape == (
        0,
        2,
    )
    with pytest.raises(Exception, match="reach"):
        coverage_stops(room, lap, reach=0.0, clearance=clearance)


def test_look_around_turns_a_full_circle_at_each_stop_and_skips_what_it_cannot_reach(corridor):
    rng = np.random.default_rng(3)
    config = get_regime("ideal").robot_config(rng)
    start = np.array([-6.45, 20.83, 1.85])
    robot = RobotBody(DiffDriveRobot(start, config, rng, world=corridor.world, odom_origin=start))
    route = free_route(corridor, config.radius + 0.15)
    nowhere = np.array([500.0, 500.0])

    def planner(a, g):  # no route leads to ``nowhere``
        return np.zeros((0, 2)) if np.allclose(g, nowhere) else route(a, g)

    axis = np.array([-7.57 - 9.45, 27.8 + 27.22])
    axis /= np.hypot(*axis)
    stops = np.array([start[:2] + 1.0 * axis, nowhere, start[:2] - 1.5 * axis])
    trace: list[np.ndarray] = []
    skipped = look_around_at(robot, stops, dt=0.1, on_step=trace.append, route=planner)
    assert skipped == 1
    poses = np.asarray(trace)
    for stop, way in zip(stops[[0, 2]], (1.0, -1.0), strict=True):
        near = np.hypot(*(poses[:, :2] - stop).T) < 0.05
        turned = np.diff(np.unwrap(poses[near, 2]))
        assert way * np.sum(turned) >= 2 * np.pi - 0.1  # anticlockwise, then clockwise
    assert np.hypot(*(robot.pose[:2] - stops[2])) < 0.05
