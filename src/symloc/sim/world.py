"""``World``: the 2D simulated world made of wall segments and circles, each with a height.

A world is a set of vertical walls standing on the floor. Each straight wall is a segment
``(x0, y0, x1, y1)`` [m]; each round obstacle (a table, a pillar, the wall of a circular room) is
a circle ``(cx, cy, r)`` [m]. Every primitive has a height [m] (a lidar mounted above it does
not see it; a camera sees it up to that height) and an integer material id that the camera turns
into a colour or a photograph (see :mod:`symloc.sim.textures`).

Material ids: ``MATERIAL_BOARD`` (plain light board), ``MATERIAL_WALL`` (plain painted wall),
``MATERIAL_FURNITURE`` (plain wood), ``MATERIAL_GLASS`` (a glass panel: the lidar's beam mostly
passes through it or returns nothing, the camera sees through it), ``MATERIAL_DARK`` (a dark,
low-reflectivity surface: the lidar often gets no return from it), ``MATERIAL_PERSON`` (a
person standing or walking), and ``MATERIAL_PHOTO + k`` for the k-th wall texture of
:mod:`symloc.sim.textures`.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import WorldError

__all__ = [
    "MATERIAL_BOARD",
    "MATERIAL_DARK",
    "MATERIAL_FURNITURE",
    "MATERIAL_GLASS",
    "MATERIAL_PERSON",
    "MATERIAL_PHOTO",
    "MATERIAL_WALL",
    "World",
    "check_polygon",
    "points_in_polygon",
    "polygon_walls",
    "segments_cross",
]

MATERIAL_BOARD = 0
MATERIAL_WALL = 1
MATERIAL_FURNITURE = 2
MATERIAL_GLASS = 3
MATERIAL_DARK = 4
MATERIAL_PERSON = 5
MATERIAL_PHOTO = 10

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

_EPS = 1e-9


def _as_float(value: ArrayLike, name: str, shape: tuple[int | None, ...]) -> FloatArray:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise WorldError(f"World.{name}: expected an array of numbers") from err
    if arr.size == 0:
        arr = arr.reshape((0, *tuple(s for s in shape[1:] if s is not None)))
    if arr.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(arr.shape, shape, strict=True)
    ):
        want_s = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise WorldError(f"World.{name}: expected shape {want_s}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise WorldError(f"World.{name}: contains NaN or infinite values")
    return arr


def _per_item(value: ArrayLike | float, n: int, name: str, dtype: type) -> NDArray[Any]:
    arr: NDArray[Any] = np.array(value, dtype=dtype)
    if arr.ndim == 0:
        arr = np.full(n, arr, dtype=dtype)
    if arr.shape != (n,):
        raise WorldError(f"World.{name}: expected one value per item ({n}), got {arr.shape}")
    return arr


@dataclass(frozen=True, eq=False)
class World:
    """Vertical walls and round obstacles standing on a flat floor.

    Parameters
    ----------
    walls : array of shape (S, 4)
        Segments ``x0, y0, x1, y1`` [m]; zero-length segments raise :class:`WorldError`.
    wall_heights : float or array of shape (S,)
        Height of each wall [m], > 0.
    wall_materials : int or array of shape (S,)
        Material id of each wall (see the module docstring).
    circles : array of shape (C, 3)
        Circles ``cx, cy, r`` [m], r > 0.
    circle_heights : float or array of shape (C,)
        Height of each circle [m], > 0.
    circle_materials : int or array of shape (C,)
        Material id of each circle.
    wall_tex_u : array of shape (S, 2), optional
        Horizontal texture coordinates (0..1) at each wall's first and second end point
        (default ``(0, 1)``: the texture spans the whole wall). Lets several short walls share
        one photograph, as the facets of a round room with a door do.
    """

    walls: FloatArray = field(default_factory=lambda: np.zeros((0, 4)))
    wall_heights: FloatArray | float = 2.5
    wall_materials: IntArray | int = MATERIAL_WALL
    circles: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    circle_heights: FloatArray | float = 0.75
    circle_materials: IntArray | int = MATERIAL_FURNITURE
    wall_tex_u: FloatArray | None = None

    def __post_init__(self) -> None:
        walls = _as_float(self.walls, "walls", (None, 4))
        circles = _as_float(self.circles, "circles", (None, 3))
        s, c = walls.shape[0], circles.shape[0]
        wh = _per_item(self.wall_heights, s, "wall_heights", np.float64)
        ch = _per_item(self.circle_heights, c, "circle_heights", np.float64)
        wm = _per_item(self.wall_materials, s, "wall_materials", np.int64)
        cm = _per_item(self.circle_materials, c, "circle_materials", np.int64)
        if self.wall_tex_u is None:
            tu = np.tile(np.array([0.0, 1.0]), (s, 1))
        else:
            tu = _as_float(self.wall_tex_u, "wall_tex_u", (s, 2))
            if np.any(np.abs(tu[:, 1] - tu[:, 0]) <= _EPS):
                raise WorldError("World.wall_tex_u: each wall needs two distinct coordinates")
        lengths = np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1])
        bad = np.flatnonzero(lengths <= _EPS)
        if bad.size:
            i = int(bad[0])
            raise WorldError(
                f"World.walls[{i}]: zero-length wall from ({walls[i, 0]}, {walls[i, 1]}) to"
                f" ({walls[i, 2]}, {walls[i, 3]}); a wall needs two distinct end points"
            )
        bad = np.flatnonzero(~(circles[:, 2] > 0)) if c else np.zeros(0, dtype=int)
        if bad.size:
            i = int(bad[0])
            raise WorldError(f"World.circles[{i}]: radius must be > 0 m, got {circles[i, 2]}")
        for name, h in (("wall_heights", wh), ("circle_heights", ch)):
            if h.size and (not np.all(np.isfinite(h)) or np.any(h <= 0)):
                i = int(np.flatnonzero(~(h > 0) | ~np.isfinite(h))[0])
                raise WorldError(f"World.{name}[{i}]: height must be a finite value > 0 m")
        for arr in (walls, circles, wh, ch, wm, cm, tu):
            arr.setflags(write=False)
        set_ = object.__setattr__
        set_(self, "walls", walls)
        set_(self, "circles", circles)
        set_(self, "wall_heights", wh)
        set_(self, "circle_heights", ch)
        set_(self, "wall_materials", wm)
        set_(self, "circle_materials", cm)
        set_(self, "wall_tex_u", tu)

    @property
    def n_walls(self) -> int:
        """Number of wall segments S."""
        return int(self.walls.shape[0])

    @property
    def n_circles(self) -> int:
        """Number of circles C."""
        return int(self.circles.shape[0])

    def __add__(self, other: World) -> World:
        """Union of two worlds (walls and circles concatenated)."""
        if not isinstance(other, World):
            return NotImplemented
        return World.merge([self, other])

    @staticmethod
    def merge(worlds: Iterable[World]) -> World:
        """Union of several worlds."""
        ws = list(worlds)
        if not ws:
            return World()
        return World(
            walls=np.concatenate([w.walls for w in ws]),
            wall_heights=np.concatenate([w.wall_heights for w in ws]),
            wall_materials=np.concatenate([w.wall_materials for w in ws]),
            circles=np.concatenate([w.circles for w in ws]),
            circle_heights=np.concatenate([w.circle_heights for w in ws]),
            circle_materials=np.concatenate([w.circle_materials for w in ws]),
            wall_tex_u=np.concatenate([np.asarray(w.wall_tex_u) for w in ws]),
        )

    def visible_above(self, min_height: float) -> World:
        """The sub-world of primitives strictly taller than ``min_height`` [m]."""
        wk = np.asarray(self.wall_heights) > min_height
        ck = np.asarray(self.circle_heights) > min_height
        return World(
            self.walls[wk],
            np.asarray(self.wall_heights)[wk],
            np.asarray(self.wall_materials)[wk],
            self.circles[ck],
            np.asarray(self.circle_heights)[ck],
            np.asarray(self.circle_materials)[ck],
            np.asarray(self.wall_tex_u)[wk],
        )

    def distance(self, points: ArrayLike, *, min_height: float = 0.0) -> FloatArray:
        """Distance ``(N,)`` [m] from points ``(N, 2)`` to the nearest wall or circle outline.

        Only primitives taller than ``min_height`` [m] count; ``inf`` if there are none.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        out = np.full(p.shape[0], np.inf)
        wk = np.asarray(self.wall_heights) > min_height
        if np.any(wk):
            w = self.walls[wk]
            a = w[None, :, :2]
            ab = w[None, :, 2:] - a
            ap = p[:, None, :] - a
            t = np.clip(np.sum(ap * ab, axis=-1) / np.sum(ab * ab, axis=-1), 0.0, 1.0)
            d = np.hypot(*(ap - t[..., None] * ab).transpose(2, 0, 1))
            out = np.minimum(out, d.min(axis=1))
        ck = np.asarray(self.circle_heights) > min_height
        if np.any(ck):
            c = self.circles[ck]
            dc = np.abs(np.hypot(p[:, None, 0] - c[:, 0], p[:, None, 1] - c[:, 1]) - c[:, 2])
            out = np.minimum(out, dc.min(axis=1))
        return out

    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` [m] of every wall and circle."""
        xs = [self.walls[:, 0], self.walls[:, 2], self.circles[:, 0] - self.circles[:, 2]]
        xs += [self.circles[:, 0] + self.circles[:, 2]]
        ys = [self.walls[:, 1], self.walls[:, 3], self.circles[:, 1] - self.circles[:, 2]]
        ys += [self.circles[:, 1] + self.circles[:, 2]]
        x = np.concatenate(xs)
        y = np.concatenate(ys)
        if x.size == 0:
            raise WorldError("World.bounds: the world is empty (no walls, no circles)")
        return float(x.min()), float(x.max()), float(y.min()), float(y.max())


def segments_cross(p1: FloatArray, p2: FloatArray, q1: FloatArray, q2: FloatArray) -> bool:
    """True if closed segments p1-p2 and q1-q2 intersect (touching counts)."""

    def orient(a: FloatArray, b: FloatArray, c: FloatArray) -> float:
        return float((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    def on_seg(a: FloatArray, b: FloatArray, c: FloatArray) -> bool:
        return bool(
            min(a[0], b[0]) - _EPS <= c[0] <= max(a[0], b[0]) + _EPS
            and min(a[1], b[1]) - _EPS <= c[1] <= max(a[1], b[1]) + _EPS
        )

    d1 = orient(q1, q2, p1)
    d2 = orient(q1, q2, p2)
    d3 = orient(p1, p2, q1)
    d4 = orient(p1, p2, q2)
    if ((d1 > _EPS and d2 < -_EPS) or (d1 < -_EPS and d2 > _EPS)) and (
        (d3 > _EPS and d4 < -_EPS) or (d3 < -_EPS and d4 > _EPS)
    ):
        return True
    return (
        (abs(d1) <= _EPS and on_seg(q1, q2, p1))
        or (abs(d2) <= _EPS and on_seg(q1, q2, p2))
        or (abs(d3) <= _EPS and on_seg(p1, p2, q1))
        or (abs(d4) <= _EPS and on_seg(p1, p2, q2))
    )


def check_polygon(vertices: ArrayLike, name: str = "polygon") -> FloatArray:
    """Validate a simple polygon and return its vertices ``(V, 2)`` counter-clockwise.

    Raises :class:`WorldError` naming the problem: fewer than 3 vertices, non-finite values,
    repeated consecutive vertices (a zero-length edge), zero area (collinear vertices) or a
    self-intersection (two non-adjacent edges cross or touch).
    """
    try:
        v = np.array(vertices, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise WorldError(f"{name}: expected (V, 2) vertex coordinates") from err
    if v.ndim != 2 or v.shape[1] != 2:
        raise WorldError(f"{name}: expected vertices of shape (V, 2), got {v.shape}")
    if v.shape[0] < 3:
        raise WorldError(f"{name}: degenerate polygon, needs >= 3 vertices, got {v.shape[0]}")
    if not np.all(np.isfinite(v)):
        raise WorldError(f"{name}: vertices contain NaN or infinite values")
    nxt = np.roll(v, -1, axis=0)
    edge_len = np.hypot(*(nxt - v).T)
    if np.any(edge_len <= _EPS):
        i = int(np.flatnonzero(edge_len <= _EPS)[0])
        raise WorldError(
            f"{name}: degenerate polygon, vertices {i} and {(i + 1) % len(v)} coincide"
            " (zero-length edge)"
        )
    n = v.shape[0]
    for i in range(n):
        for j in range(i + 1, n):
            if j == i + 1 or (i == 0 and j == n - 1):
                continue
            if segments_cross(v[i], nxt[i], v[j], nxt[j]):
                raise WorldError(f"{name}: self-intersecting polygon, edge {i} crosses edge {j}")
    area2 = float(np.sum(v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]))
    scale = float(np.max(edge_len)) ** 2
    if abs(area2) <= 1e-9 * scale:
        raise WorldError(f"{name}: degenerate polygon with zero area (collinear vertices)")
    if area2 < 0:
        v = v[::-1].copy()
    return v


def polygon_walls(
    vertices: ArrayLike,
    *,
    door: tuple[int, float, float] | None = None,
    name: str = "polygon",
) -> FloatArray:
    """The wall segments ``(S, 4)`` of a closed polygon, optionally with one door gap.

    Parameters
    ----------
    vertices : array of shape (V, 2)
        Polygon corners [m]; validated by :func:`check_polygon` (then ordered
        counter-clockwise, edge i runs from vertex i to vertex i+1).
    door : (edge, width, position), optional
        Leave a gap of ``width`` [m] in edge ``edge`` centred at fraction ``position`` (0..1)
        along it.
    """
    v = check_polygon(vertices, name)
    nxt = np.roll(v, -1, axis=0)
    segs = [np.concatenate([a, b]) for a, b in zip(v, nxt, strict=True)]
    if door is not None:
        edge, width, pos = int(door[0]), float(door[1]), float(door[2])
        if not 0 <= edge < len(segs):
            raise WorldError(f"{name}: door edge {edge} out of range 0..{len(segs) - 1}")
        a, b = v[edge], nxt[edge]
        length = float(np.hypot(*(b - a)))
        half = width / 2.0 / length
        lo, hi = pos - half, pos + half
        if width <= 0 or lo <= 1e-6 or hi >= 1 - 1e-6:
            raise WorldError(
                f"{name}: door of width {width} m at {pos} does not fit in edge {edge}"
                f" of length {length:.3f} m"
            )
        p_lo = a + lo * (b - a)
        p_hi = a + hi * (b - a)
        segs[edge : edge + 1] = [np.concatenate([a, p_lo]), np.concatenate([p_hi, b])]
    return np.array(segs, dtype=np.float64)


def points_in_polygon(points: ArrayLike, polygon: ArrayLike) -> NDArray[np.bool_]:
    """``(N,)`` True where points ``(N, 2)`` lie inside the polygon ``(V, 2)`` (even-odd rule)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    v = np.asarray(polygon, dtype=np.float64)
    a = v[None, :, :]
    b = np.roll(v, -1, axis=0)[None, :, :]
    out = np.zeros(p.shape[0], dtype=bool)
    step = max(1, 2_000_000 // max(1, v.shape[0]))  # bound the (N, V) temporaries
    for i in range(0, p.shape[0], step):
        px, py = p[i : i + step, None, 0], p[i : i + step, None, 1]
        straddle = (a[..., 1] > py) != (b[..., 1] > py)
        with np.errstate(divide="ignore", invalid="ignore"):
            dx = (b[..., 0] - a[..., 0]) / (b[..., 1] - a[..., 1])
            x_cross = a[..., 0] + (py - a[..., 1]) * dx
        crossings = np.count_nonzero(straddle & (px < x_cross), axis=1)
        out[i : i + step] = (crossings % 2) == 1
    return out
