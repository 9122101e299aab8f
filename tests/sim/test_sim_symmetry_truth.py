"""The ground-truth symmetry order, computed from the geometry."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from symloc.errors import ConfigurationError, WorldError
from symloc.sim.symmetry_truth import (
    lidar_symmetry,
    lidar_visible,
    outline_centroid,
    rotational_order,
)
from symloc.sim.world import MATERIAL_GLASS, MATERIAL_PERSON, World, polygon_walls
from symloc.sim.world_file import WorldSpec


def _world(**doc: Any) -> WorldSpec:
    return WorldSpec.from_dict({"name": "t", **doc})


def _order(**doc: Any) -> int:
    return _world(**doc).build().order


def _ngon(n: int, r: float, c: tuple[float, float] = (0.0, 0.0), yaw: float = 0.0) -> np.ndarray:
    a = yaw + 2 * math.pi * np.arange(n) / n
    return np.column_stack([c[0] + r * np.cos(a), c[1] + r * np.sin(a)])


@pytest.mark.parametrize("n", range(3, 13))
def test_regular_ngons_give_n_wherever_they_stand(n: int) -> None:
    v = _ngon(n, 1.5 + 0.5 * n, c=(3.0, -7.0), yaw=0.3 * n)
    truth = lidar_symmetry(World(polygon_walls(v)), v)
    assert truth.order == n
    assert np.allclose(truth.center, [3.0, -7.0], atol=1e-9)
    assert truth.gv_distance == pytest.approx(1.5 + 0.5 * n)
    assert truth.symmetric
    assert not truth.continuous
    assert not truth.open


@pytest.mark.parametrize(
    ("room", "order"),
    [
        ({"rectangle": {"width": 5.0, "depth": 3.0}}, 2),
        ({"rectangle": {"width": 3.0, "depth": 3.0}}, 4),
        ({"polygon": [[-2, -2], [2, -2], [2, 2], [-2, 2]]}, 4),
        ({"circle": {"radius": 3.0}}, 0),
        ({"corridor": {"length": 50.0, "width": 2.0, "yaw_deg": 30}}, 2),
        ({"polygon": [[0, 0], [4, 0], [4, 2], [2, 2], [2, 4], [0, 4]]}, 1),  # L
        ({"polygon": [[0, -2], [1.5, 0], [0, 1], [-1.5, 0]]}, 1),  # kite
        ({"polygon": [[0, 0], [4, 0], [5.5, 2.5], [1.5, 2.5]]}, 2),  # parallelogram
    ],
)
def test_shapes(room: dict[str, Any], order: int) -> None:
    assert _order(room=room) == order


def test_cross_is_four_fold() -> None:
    h, e = 1.0, 3.0
    v = [[h, -h], [e, -h], [e, h], [h, h], [h, e], [-h, e], [-h, h], [-e, h], [-e, -h]]
    v += [[-h, -h], [-h, -e], [h, -e]]
    assert _order(room={"polygon": v}) == 4
    v[1][0] = e + 0.5  # one arm longer
    v[2][0] = e + 0.5
    assert _order(room={"polygon": v}) == 1


SQUARE = {"polygon": [[-2, -2], [2, -2], [2, 2], [-2, 2]]}


def test_door_or_one_box_breaks_the_square() -> None:
    assert _order(room=SQUARE, doors=[{"wall": 0, "at": 0.5, "width": 0.9}]) == 1
    box = {"box": {"center": [1.45, 0.0], "size": [0.5, 0.5], "height": 0.8}}
    assert _order(room=SQUARE, furniture=[box]) == 1
    assert _order(room={"circle": {"radius": 3.0}}, doors=[{"wall": 0, "width": 0.9}]) == 1


def test_what_the_lidar_does_not_see_keeps_the_symmetry() -> None:
    low = {"box": {"center": [1.0, 0.0], "size": [0.5, 0.5], "height": 0.25}}
    assert _order(room=SQUARE, furniture=[low]) == 4
    closed = {"wall": 0, "at": 0.3, "width": 0.9, "open": False}
    assert _order(room=SQUARE, doors=[closed]) == 4
    glass = [{"from": [0.5, 1.0], "to": [1.5, 1.0]}]
    world = _world(room=SQUARE, glass=glass).build()
    assert world.order == 4
    assert lidar_symmetry(world.world, world.boundary, glass_visible=True).order == 1
    people = [{"path": [[-1, -1], [1, -1]]}]
    room = _world(room=SQUARE, people=people).build()
    assert room.order == 4
    assert lidar_visible(room.world_at(0.5)).n_circles == 0  # people are not counted


def test_four_boxes_in_a_square_stay_four_fold_and_chamfers() -> None:
    boxes = [
        {"box": {"center": [x, y], "size": [0.4, 0.3], "yaw_deg": yaw, "height": 0.8}}
        for x, y, yaw in [(1.0, 0.5, 0), (-0.5, 1.0, 90), (-1.0, -0.5, 180), (0.5, -1.0, 270)]
    ]
    assert _order(room=SQUARE, furniture=boxes) == 4
    assert _order(room={**SQUARE, "chamfer": 0.3}) == 4
    assert _order(room={**SQUARE, "chamfer": [0.3, 0.3, 0.3, 0.1]}) == 1
    assert _order(room={**SQUARE, "chamfer": [0.3, 0.1, 0.3, 0.1]}) == 2


def test_tolerance_one_centimetre() -> None:
    v = _ngon(6, 3.0)
    v_small = v.copy()
    v_small[0] += [0.004, 0.0]  # 4 mm: still six-fold at 1 cm
    v_big = v.copy()
    v_big[0] += [0.05, 0.0]  # 5 cm: not
    assert rotational_order(World(polygon_walls(v_small)), np.zeros(2))[0] == 6
    assert rotational_order(World(polygon_walls(v_big)))[0] == 1
    assert rotational_order(World(polygon_walls(v_big)), tolerance=0.1)[0] == 6


def test_fine_polygons_are_continuous_and_near_misses_rejected() -> None:
    fine = _ngon(96, 3.0)  # sagitta 1.6 mm: a circle at 1 cm
    assert rotational_order(World(polygon_walls(fine)))[0] == 0
    assert rotational_order(World(polygon_walls(_ngon(16, 1.5))))[0] == 16  # not 18


def test_low_boards_let_the_lidar_see_the_lab() -> None:
    room = _world(room={**SQUARE, "wall_height": 0.25}).build()  # below the 0.3 m plane
    assert room.symmetry is not None
    assert room.symmetry.open
    assert room.order == 2  # the 8 m x 10 m lab around it
    boards = _world(room={**SQUARE, "wall_height": 0.4}).build()
    assert boards.order == 4
    assert boards.symmetry is not None
    assert not boards.symmetry.open


def test_centroid_and_errors() -> None:
    w = World(np.array([[0.0, 0.0, 2.0, 0.0]]), circles=np.array([[10.0, 0.0, 1.0]]))
    c = outline_centroid(w)
    assert c[0] == pytest.approx((2 * 1.0 + 2 * math.pi * 10.0) / (2 + 2 * math.pi))
    with pytest.raises(WorldError, match="no walls and no circles"):
        outline_centroid(World())
    with pytest.raises(WorldError, match="nothing in the world is taller than the lidar plane"):
        lidar_symmetry(World(np.array([[0.0, 0.0, 1.0, 0.0]]), 0.1))
    with pytest.raises(ConfigurationError, match="max_order: expected an integer >= 2"):
        rotational_order(World(polygon_walls(_ngon(4, 1.0))), max_order=1)
    with pytest.raises(ConfigurationError, match="tolerance"):
        rotational_order(World(polygon_walls(_ngon(4, 1.0))), tolerance=0.0)


def test_materials_filter() -> None:
    w = World(
        np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 1.0, 1.0, 1.0]]),
        wall_materials=np.array([MATERIAL_GLASS, 1]),
        circles=np.array([[0.0, 0.0, 0.2]]),
        circle_heights=1.7,
        circle_materials=MATERIAL_PERSON,
    )
    assert lidar_visible(w).n_walls == 1
    assert lidar_visible(w, glass_visible=True).n_walls == 2
    assert lidar_visible(w).n_circles == 0


def test_room_truth_with_opaque_glass() -> None:
    room = _world(room=SQUARE, glass=[{"from": [0.5, 1.0], "to": [1.5, 1.0]}]).build()
    assert room.truth() is room.symmetry
    assert room.truth().order == 4
    assert room.truth(glass_visible=True).order == 1
    plain = _world(room=SQUARE).build()
    assert plain.truth(glass_visible=True).order == 4


def test_near_symmetry_overlap() -> None:
    from symloc.sim.symmetry_truth import near_symmetry_overlap

    bare = _world(room=SQUARE).build()
    assert near_symmetry_overlap(bare.world, bare.boundary, 4) == pytest.approx(1.0)
    box = {"box": {"center": [1.45, 0.0], "size": [0.5, 0.5], "height": 0.8}}
    room = _world(room=SQUARE, furniture=[box]).build()
    assert room.order == 1
    # the box's outline (2 m) against the walls' (16 m): about 8/9 of the map lands on itself
    for k in (2, 4):
        share = near_symmetry_overlap(room.world, room.boundary, k, [0.0, 0.0])
        assert share == pytest.approx(16 / 18, abs=0.01)
    low = {"box": {"center": [1.0, 0.0], "size": [0.5, 0.5], "height": 0.2}}
    room = _world(room=SQUARE, furniture=[low]).build()
    assert near_symmetry_overlap(room.world, room.boundary, 4) == pytest.approx(1.0)
    with pytest.raises(ConfigurationError, match="order"):
        near_symmetry_overlap(room.world, room.boundary, 1)
