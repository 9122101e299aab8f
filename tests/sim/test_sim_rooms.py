"""Room builders and the Room ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError, WorldError
from symloc.sim.rooms import (
    ROOM_NAMES,
    build_room,
    circular_room,
    l_shaped_room,
    lab,
    rectangle_room,
    regular_polygon_room,
)
from symloc.sim.world import MATERIAL_BOARD, MATERIAL_PHOTO, MATERIAL_WALL


@pytest.mark.parametrize("n", [3, 4, 5, 6, 8])
def test_regular_polygon_ground_truth(n: int) -> None:
    room = regular_polygon_room(n, 3.0, center=(1.0, -2.0))
    assert room.kind == "polygon"
    assert room.order == room.shape_order == n
    assert np.allclose(room.center, [1.0, -2.0])
    assert np.allclose(np.hypot(*(room.corners - room.center).T), 3.0)
    sides = np.hypot(*(np.roll(room.corners, -1, axis=0) - room.corners).T)
    assert np.allclose(sides, 2 * 3.0 * math.sin(math.pi / n))
    # bottom edge horizontal
    assert math.isclose(room.corners[0, 1], room.corners[1, 1])


def test_square_of_paper_is_three_by_three() -> None:
    room = build_room("square", 1.5 * math.sqrt(2), lab=True)
    assert np.allclose(room.boundary.max(axis=0) - room.boundary.min(axis=0), [3.0, 3.0])
    boards = np.asarray(room.world.wall_materials) == MATERIAL_BOARD
    assert boards.sum() == 4
    assert np.allclose(np.asarray(room.world.wall_heights)[boards], 0.4)
    photos = np.asarray(room.world.wall_materials) >= MATERIAL_PHOTO
    assert photos.sum() == 12
    assert len(set(np.asarray(room.world.wall_materials)[photos].tolist())) == 12
    assert room.wall_height == 0.4


def test_plain_lab_has_no_photos() -> None:
    room = build_room("square", 2.0, textured=False)
    assert not np.any(np.asarray(room.world.wall_materials) >= MATERIAL_PHOTO)
    assert np.sum(np.asarray(room.world.wall_materials) == MATERIAL_WALL) == 12


@pytest.mark.parametrize("name", ROOM_NAMES)
def test_build_room_every_name(name: str) -> None:
    room = build_room(name, 4.0, lab=False)
    assert room.name == name
    assert room.order == room.shape_order
    assert room.gv_distance == pytest.approx(4.0)
    expected = {"circle": 0, "rectangle": 2, "hallway": 2, "l_shaped": 1}
    if name in expected:
        assert room.order == expected[name]
    assert room.contains(room.center[None])[0]


def test_door_and_furniture_break_symmetry() -> None:
    assert build_room("square", 3.0, door=True).order == 1
    assert build_room("circle", 3.0, door=True).order == 1
    room = build_room("hexagon", 3.0, furniture=2, tables=2, rng=4)
    assert room.order == 1
    assert room.shape_order == 6
    assert room.n_furniture == 4
    assert room.world.n_circles == 2
    assert room.symmetric is False
    same = build_room("hexagon", 3.0, furniture=2, tables=2, rng=4)
    assert np.array_equal(room.world.walls, same.world.walls)


def test_door_gap_is_open() -> None:
    room = build_room("square", 3.0, door=True, lab=False)
    bottom_mid = np.array([[0.0, room.boundary[:, 1].min()]])
    assert room.world.distance(bottom_mid)[0] == pytest.approx(0.4)


def test_circular_room_is_one_circle() -> None:
    room = circular_room(2.5)
    assert room.world.n_walls == 0
    assert room.world.n_circles == 1
    assert room.order == 0
    assert room.symmetric
    assert room.area == pytest.approx(math.pi * 2.5**2, rel=0.01)


def test_rectangle_and_l_shape() -> None:
    r = rectangle_room(4.0, 2.0)
    assert r.shape_order == 2
    assert r.gv_distance == pytest.approx(math.hypot(2, 1))
    assert rectangle_room(3.0, 3.0).shape_order == 4
    ell = l_shaped_room(4.0)
    assert ell.area == pytest.approx(12.0)
    assert np.allclose(ell.center, 0.0, atol=1e-12)


def test_lab_segments() -> None:
    w = lab(8.0, 10.0, n_segments=12)
    assert w.n_walls == 12
    lengths = np.hypot(w.walls[:, 2] - w.walls[:, 0], w.walls[:, 3] - w.walls[:, 1])
    assert lengths.sum() == pytest.approx(36.0)
    with pytest.raises(WorldError, match="n_segments must be an integer >= 4"):
        lab(n_segments=3)


def test_lab_grows_around_large_rooms() -> None:
    room = build_room("octagon", 7.0)
    photos = np.asarray(room.world.wall_materials) >= MATERIAL_PHOTO
    lab_walls = room.world.walls[photos]
    span = np.ptp(room.boundary[:, 0])
    assert np.ptp(lab_walls[:, [0, 2]]) >= span + 3.0 - 1e-9


@settings(max_examples=25, deadline=None)
@given(
    name=st.sampled_from(["triangle", "square", "hexagon", "circle", "l_shaped", "rectangle"]),
    gv=st.floats(2.0, 7.0),
    n=st.integers(1, 60),
    margin=st.floats(0.0, 0.5),
)
def test_positions_inside(name: str, gv: float, n: int, margin: float) -> None:
    room = build_room(name, gv, lab=False)
    pts = room.positions_inside(n, margin)
    assert pts.shape == (n, 2)
    assert np.all(room.contains(pts))
    assert np.all(room.world.distance(pts) >= margin - 1e-9)
    assert len(np.unique(pts, axis=0)) == n


def test_positions_spread_evenly() -> None:
    room = build_room("square", 3.0, lab=False)
    pts = room.positions_inside(49, 0.3)
    # spread over the whole room, not bunched on one side
    assert np.all(np.abs(pts.mean(axis=0) - room.center) < 0.3)
    assert np.ptp(pts[:, 0]) > 2.5
    assert np.ptp(pts[:, 1]) > 2.5


def test_bad_inputs_raise() -> None:
    with pytest.raises(ConfigurationError, match="unknown room name 'dodecahedron'"):
        build_room("dodecahedron", 3.0)
    with pytest.raises(ConfigurationError, match="gv: expected a value > 0"):
        build_room("square", 0.0)
    with pytest.raises(WorldError, match="n must be an integer >= 3"):
        regular_polygon_room(2, 3.0)
    with pytest.raises(ConfigurationError, match="n must be an integer >= 1"):
        build_room("square", 3.0).positions_inside(0)
    with pytest.raises(WorldError, match="too small"):
        build_room("square", 0.5, lab=False).positions_inside(5, margin=1.0)
    with pytest.raises(ConfigurationError, match="boxes must be an integer >= 0"):
        build_room("square", 3.0, furniture=-1)
