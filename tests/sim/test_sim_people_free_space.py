"""People walking, free space, uniform pose sampling."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import WorldError
from symloc.lidar_spec import RPLIDAR_A2
from symloc.sim.lidar import simulate_scan
from symloc.sim.people import Person, people_world
from symloc.sim.rooms import build_room
from symloc.sim.world import MATERIAL_PERSON, World
from symloc.sim.world_file import WorldSpec


def test_person_walks_there_and_back() -> None:
    p = Person(np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0]]), speed=1.0)
    assert p.length == pytest.approx(3.0)
    assert p.period == pytest.approx(6.0)
    pos = p.positions([0.0, 1.0, 2.5, 3.0, 4.0, 6.0, 7.0])
    assert np.allclose(pos, [[0, 0], [1, 0], [2, 0.5], [2, 1], [2, 0], [0, 0], [1, 0]])
    loop = Person(np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]]), speed=2.0, loop=True, phase=1.0)
    assert loop.period == pytest.approx((4 + math.sqrt(8)) / 2)
    assert np.allclose(loop.position(0.0), [1.0, 0.0])
    assert np.allclose(loop.position(loop.period), [1.0, 0.0])
    w = people_world([p, loop], 1.0)
    assert w.n_circles == 2
    assert set(np.asarray(w.circle_materials).tolist()) == {MATERIAL_PERSON}
    assert np.allclose(w.circle_heights, 1.7)
    assert people_world([], 0.0).n_circles == 0


def test_a_person_whose_path_crosses_the_robot_steps_aside() -> None:
    p = Person(np.array([[-2.0, 0.0], [2.0, 0.0]]), speed=1.0, radius=0.25)
    robot = np.array([0.1, 0.05, 0.0])  # the person walks through here at t = 2.1 s
    plain = people_world([p], 2.1).circles[0]
    assert math.hypot(*(plain[:2] - robot[:2])) < 0.1
    aside = people_world([p], 2.1, (robot, 0.18)).circles[0]
    # just touching the robot, straight away from its centre; a person clear of it is left
    assert math.hypot(*(aside[:2] - robot[:2])) == pytest.approx(0.43)
    far = people_world([p], 0.0, (robot, 0.18)).circles[0]
    assert np.allclose(far, people_world([p], 0.0).circles[0])
    # in a 4 m square the lidar sees the walls past the person, not the person all round
    b = np.array([[-2.0, -2.0], [2.0, -2.0], [2.0, 2.0], [-2.0, 2.0]])
    walls = World(np.column_stack([b, np.roll(b, -1, axis=0)]))
    inside = simulate_scan(walls + people_world([p], 2.1), robot, RPLIDAR_A2, noise=False)
    beside = simulate_scan(
        walls + people_world([p], 2.1, (robot, 0.18)), robot, RPLIDAR_A2, noise=False
    )
    assert np.mean(np.asarray(inside.ranges) > 1.0) < 0.05
    assert np.mean(np.asarray(beside.ranges) > 1.0) > 0.6
    for bad in ((np.array([1.0]), 0.18), (np.array([np.nan, 0.0]), 0.18), (robot, -0.1)):
        with pytest.raises(WorldError, match="clear_of"):
            people_world([p], 2.1, bad)


@settings(max_examples=30, deadline=None)
@given(t=st.floats(0.0, 1e4), speed=st.floats(0.3, 2.0))
def test_person_speed_and_path(t: float, speed: float) -> None:
    p = Person(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0]]), speed=speed)
    a, b = p.positions([t, t + 0.1])
    assert float(np.hypot(*(b - a))) <= speed * 0.1 + 1e-9  # never faster than walking
    assert -1e-9 <= a[0] <= 3 + 1e-9
    assert -1e-9 <= a[1] <= 2 + 1e-9


def test_person_errors() -> None:
    with pytest.raises(WorldError, match=r"Person.waypoints: expected >= 2 finite"):
        Person(np.array([[0.0, 0.0]]))
    with pytest.raises(WorldError, match=r"Person.speed: expected a finite value > 0"):
        Person(np.array([[0.0, 0.0], [1.0, 0.0]]), speed=0.0)
    with pytest.raises(WorldError, match=r"Person.waypoints\[1\]: repeats the waypoint"):
        Person(np.array([[0.0, 0.0], [0.0, 0.0]]))
    with pytest.raises(WorldError, match=r"Person.phase"):
        Person(np.array([[0.0, 0.0], [1.0, 0.0]]), phase=-1.0)


BOXED = {
    "name": "boxed",
    "room": {"rectangle": {"width": 4.0, "depth": 3.0}},
    "furniture": [
        {"box": {"center": [1.0, 0.5], "size": [0.8, 0.6], "height": 0.2}},  # below the lidar
        {"cylinder": {"center": [-1.0, -0.5], "radius": 0.3}},
    ],
}


def test_is_free_counts_low_furniture_and_interiors() -> None:
    room = WorldSpec.from_dict(BOXED).build()
    assert room.order == 1  # the round table is seen by the lidar
    pts = np.array([[1.0, 0.5], [-1.0, -0.5], [0.0, 0.0], [1.9, 0.0], [5.0, 0.0]])
    free = room.is_free(pts, 0.18)
    assert free.tolist() == [False, False, True, False, False]
    assert room.is_free(np.array([[1.75, 0.0]]), 0.18)[0]  # 0.25 m from the wall: fits
    assert not room.is_free(np.array([[1.75, 0.0]]), 0.3)[0]


def test_sample_pose_is_uniform_and_reaches_the_walls() -> None:
    room = WorldSpec.from_dict(BOXED).build()
    rng = np.random.default_rng(3)
    poses = np.array([room.sample_pose(rng, 0.18) for _ in range(400)])
    assert np.all(room.is_free(poses[:, :2], 0.18))
    # poses come within a few cm of the clearance limit (not a coarse grid)
    assert poses[:, 0].max() > 2.0 - 0.18 - 0.05
    assert poses[:, 1].min() < -1.5 + 0.18 + 0.05
    # uniform: the left and right halves get shares close to their free areas
    left = np.mean(poses[:, 0] < 0)
    assert 0.4 < left < 0.62
    assert np.ptp(poses[:, 2]) > 5.5


def test_reachable_component_excludes_a_sealed_pocket() -> None:
    # a box in the corner leaves a pocket behind it too narrow to reach
    doc = {
        "name": "pocket",
        "room": {"rectangle": {"width": 4.0, "depth": 4.0}},
        "furniture": [
            {"box": {"center": [1.1, 1.1], "size": [1.2, 1.2], "yaw_deg": 45, "height": 0.2}}
        ],
    }
    room = WorldSpec.from_dict(doc).build()
    fs = room.free_space(0.18)
    assert fs.n_components >= 2
    corner = np.array([[1.75, 1.75]])
    assert room.is_free(corner, 0.18)[0]
    assert not room.is_reachable(corner, 0.18)[0]
    assert room.is_reachable(room.center[None], 0.18)[0]
    rng = np.random.default_rng(0)
    poses = np.array([room.sample_pose(rng) for _ in range(100)])
    assert np.all(room.is_reachable(poses[:, :2]))
    assert fs.reachable_area < fs.free_area


def test_sample_pose_in_the_named_rooms_and_errors() -> None:
    room = build_room("hexagon", 2.0, furniture=2, rng=1)
    pose = room.sample_pose(5)
    assert room.is_free(pose[None, :2])[0]
    tiny = WorldSpec.from_dict(
        {"name": "tiny", "room": {"rectangle": {"width": 0.5, "depth": 0.5}}}
    ).build()
    with pytest.raises(
        WorldError, match=r"no place in room .tiny. where a robot of radius 0\.3 m fits"
    ):
        tiny.sample_pose(0, 0.3)
