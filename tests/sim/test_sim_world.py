"""World validation, polygon checks and distances."""

from __future__ import annotations

import numpy as np
import pytest

from symloc.errors import WorldError
from symloc.sim.world import World, check_polygon, polygon_walls


def test_zero_length_wall_raises() -> None:
    with pytest.raises(WorldError, match=r"walls\[1\]: zero-length wall"):
        World(walls=[[0, 0, 1, 0], [2, 2, 2, 2]])


def test_non_positive_radius_raises() -> None:
    with pytest.raises(WorldError, match=r"circles\[0\]: radius must be > 0"):
        World(circles=[[0, 0, 0.0]])
    with pytest.raises(WorldError, match="radius must be > 0"):
        World(circles=[[0, 0, 1.0], [1, 1, -0.5]])


def test_bad_heights_and_shapes_raise() -> None:
    with pytest.raises(WorldError, match=r"wall_heights\[0\]: height must be"):
        World(walls=[[0, 0, 1, 0]], wall_heights=0.0)
    with pytest.raises(WorldError, match=r"expected shape \(N, 4\)"):
        World(walls=[[0, 0, 1]])
    with pytest.raises(WorldError, match="one value per item"):
        World(walls=[[0, 0, 1, 0]], wall_heights=[1.0, 2.0])
    with pytest.raises(WorldError, match="NaN or infinite"):
        World(walls=[[0, 0, np.nan, 0]])


def test_degenerate_polygons_raise() -> None:
    with pytest.raises(WorldError, match="needs >= 3 vertices"):
        check_polygon([[0, 0], [1, 0]])
    with pytest.raises(WorldError, match="coincide"):
        check_polygon([[0, 0], [1, 0], [1, 0], [0, 1]])
    with pytest.raises(WorldError, match="zero area"):
        check_polygon([[0, 0], [1, 0], [2, 0]])
    with pytest.raises(WorldError, match="self-intersecting polygon, edge 0 crosses edge 2"):
        check_polygon([[0, 0], [1, 1], [1, 0], [0, 1]])  # a bow tie


def test_polygon_is_made_counter_clockwise_and_closed() -> None:
    cw = [[0, 0], [0, 1], [1, 1], [1, 0]]
    v = check_polygon(cw)
    nxt = np.roll(v, -1, axis=0)
    assert np.sum(v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]) > 0
    walls = polygon_walls(cw)
    assert walls.shape == (4, 4)
    assert np.allclose(walls[:, 2:], np.roll(walls[:, :2], -1, axis=0))


def test_door_gap_splits_edge() -> None:
    walls = polygon_walls([[0, 0], [4, 0], [4, 4], [0, 4]], door=(0, 1.0, 0.5))
    assert walls.shape == (5, 4)
    assert np.allclose(walls[0], [0, 0, 1.5, 0])
    assert np.allclose(walls[1], [2.5, 0, 4, 0])
    with pytest.raises(WorldError, match="does not fit"):
        polygon_walls([[0, 0], [1, 0], [1, 1], [0, 1]], door=(0, 1.5, 0.5))
    with pytest.raises(WorldError, match="door edge 7 out of range"):
        polygon_walls([[0, 0], [1, 0], [1, 1], [0, 1]], door=(7, 0.2, 0.5))


def test_merge_visible_above_and_distance() -> None:
    low = World(walls=[[0, 0, 1, 0]], wall_heights=0.4)
    tall = World(circles=[[5, 0, 1]], circle_heights=2.0)
    both = low + tall
    assert (both.n_walls, both.n_circles) == (1, 1)
    assert both.visible_above(0.5).n_walls == 0
    assert both.visible_above(0.5).n_circles == 1
    d = both.distance([[0.5, 1.0], [5, 0], [3, 0]])
    assert np.allclose(d, [1.0, 1.0, 1.0])
    d_high = both.distance([[0.5, 1.0]], min_height=0.5)
    assert np.allclose(d_high, [np.hypot(4.5, 1.0) - 1.0])
    assert both.bounds() == (0.0, 6.0, -1.0, 1.0)
    with pytest.raises(WorldError, match="empty"):
        World().bounds()


def test_arrays_are_read_only() -> None:
    w = World(walls=[[0, 0, 1, 0]])
    with pytest.raises(ValueError, match="read-only"):
        w.walls[0, 0] = 3.0


def test_wall_texture_coordinates() -> None:
    w = World(walls=[[0, 0, 1, 0], [1, 0, 2, 0]], wall_tex_u=[[0.0, 0.5], [0.5, 1.0]])
    assert np.allclose(w.wall_tex_u, [[0.0, 0.5], [0.5, 1.0]])
    plain = World(walls=[[0, 0, 0, 1]])
    assert np.allclose(plain.wall_tex_u, [[0.0, 1.0]])
    merged = w + plain
    assert merged.wall_tex_u.shape == (3, 2)
    assert np.allclose(merged.visible_above(0.0).wall_tex_u, merged.wall_tex_u)
    with pytest.raises(WorldError, match="wall_tex_u: each wall needs two distinct"):
        World(walls=[[0, 0, 1, 0]], wall_tex_u=[[0.3, 0.3]])
    with pytest.raises(WorldError, match=r"wall_tex_u: expected shape \(1, 2\)"):
        World(walls=[[0, 0, 1, 0]], wall_tex_u=[[0.0, 0.5], [0.5, 1.0]])
