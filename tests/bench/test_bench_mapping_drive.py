"""The mapping trip's driver: around furniture, along a whole corridor (bench.exploration)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from symloc.bench.episode import RobotBody, drive_waypoints
from symloc.bench.exploration import _line_free, exploration_path, free_route
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
