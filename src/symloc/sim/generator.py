"""Worlds drawn from families of rooms, deterministically from a seed.

``generate_world(family, seed)`` returns a validated :class:`~symloc.sim.world_file.WorldSpec`
(so ``symloc sim world --family F --seed S --out F.yaml`` can write it out for a user to edit).
Each family draws a room shape from its parameter ranges (:data:`FAMILIES`); with ``perturb``
the room then gets one to three perturbations:

``chamfer``
    every corner cut by 0.05-0.5 m, equal cuts (half the time; the symmetry stays) or one cut
    per corner (it breaks);
``furniture``
    one to three boxes or round tables taller than the lidar plane (0.5-1.2 m: they break the
    symmetry) or lower than it (0.1-0.25 m: the lidar does not see them, the robot still bumps
    into them);
``symmetric_furniture``
    one item repeated k times round the centre of a k-fold room (the symmetry stays);
``door``
    a door, open (a gap: breaks the symmetry) or closed (a wooden leaf flush with the wall: it
    stays for the lidar, the camera sees the door);
``pillars``
    one or two full-height pillars off the centre;
``glass``
    a free-standing glass panel (transparent to the lidar, so the symmetry stays);
``people``
    one to three people walking at 0.8-1.3 m/s (the static symmetry stays);
``aliasing``
    two walls (or lab segments) showing the same texture;
``dark``
    one wall of dark, poorly reflecting material.

The ``furnished`` family (:mod:`symloc.sim.furnished`) is a symmetric base room that every
world furnishes a little (furniture or a pillar grid that breaks the symmetry only slightly); it
records the base order and the near-symmetry overlap in the world's ``metadata``, and its
perturbed worlds only get the perturbations that leave the lidar's static geometry alone.

The order is never assumed: it is computed from the geometry when the world is built
(``WorldSpec.build().order``), so a perturbation that breaks the symmetry gives order 1. Every
generated world is checked to be valid (furniture apart and inside, people's paths clear, a
robot of radius 0.18 m fits, and where the room is symmetric it can stand at the centre and
reach it from most of the room); a draw that fails is drawn again from the same stream.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull

from symloc.errors import ConfigurationError, WorldError
from symloc.sim import furnished
from symloc.sim.rooms import BOARD_HEIGHT, ROBOT_RADIUS, Room
from symloc.sim.world_build import assemble, corner_points
from symloc.sim.world_file import WorldSpec
from symloc.sim.world_spec import (
    TEXTURE_POOL,
    DoorSpec,
    FurnitureSpec,
    GlassSpec,
    LabSpec,
    PersonSpec,
    RoomSpec,
)

__all__ = [
    "FAMILIES",
    "LIDAR_RANGE",
    "PERTURBATIONS",
    "Family",
    "generate_world",
]

FloatArray = NDArray[np.float64]

LIDAR_RANGE = 16.0
"""Range [m] of the lidar that corridor ends are visible to (or not) from the middle."""
PERTURBATIONS = (
    "chamfer",
    "furniture",
    "symmetric_furniture",
    "door",
    "pillars",
    "glass",
    "people",
    "aliasing",
    "dark",
)
"""Perturbation kinds (see the module docstring)."""

_ATTEMPTS = 40
_CENTRE_FREE = 0.6  # keep this much [m] (plus the item) clear round the centre of a symmetric room


@dataclass(frozen=True)
class Family:
    """A family of rooms.

    Attributes
    ----------
    name : str
    description : str
    symmetric : bool
        True if every unperturbed room of the family has a rotational symmetry (order >= 2, or
        0 for a circle) by construction; the order itself is computed, not declared.
    params : mapping of str to (low, high)
        Parameter ranges (units in the names).
    draw : callable
        ``draw(rng) -> RoomSpec`` (shape only; the generator picks the wall height).
    tall_only : bool
        Never put in a lab of low boards (corridors).
    furnish : callable or None
        ``furnish(spec, rng) -> WorldSpec``: a step every world of the family takes after its
        shape is drawn and before any perturbation (the ``furnished`` family places its
        furniture and records its metadata here); it raises
        :class:`~symloc.errors.WorldError` to have the world drawn again.
    perturbations : tuple of str
        The perturbation kinds (of :data:`PERTURBATIONS`) the family's perturbed worlds draw
        from.
    nearly_symmetric : bool
        Every room is symmetric but for a little furniture (the ``furnished`` family): validated
        as a symmetric room (a robot stands at the centre and reaches most of the room).
    """

    name: str
    description: str
    symmetric: bool
    params: Mapping[str, tuple[float, float]]
    draw: Callable[[np.random.Generator], RoomSpec]
    tall_only: bool = False
    furnish: Callable[[WorldSpec, np.random.Generator], WorldSpec] | None = None
    perturbations: tuple[str, ...] = PERTURBATIONS
    nearly_symmetric: bool = False


def _poly(v: FloatArray) -> RoomSpec:
    v = v - _centroid(v)
    return RoomSpec(
        "polygon", polygon=tuple((round(float(x), 4), round(float(y), 4)) for x, y in v)
    )


def _centroid(v: FloatArray) -> FloatArray:
    nxt = np.roll(v, -1, axis=0)
    cross = v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]
    a = cross.sum() / 2.0
    return np.array(
        [
            np.sum((v[:, 0] + nxt[:, 0]) * cross) / (6 * a),
            np.sum((v[:, 1] + nxt[:, 1]) * cross) / (6 * a),
        ]
    )


def _rotate(v: FloatArray, angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.asarray(v @ np.array([[c, -s], [s, c]]).T, dtype=np.float64)


def _u(rng: np.random.Generator, lo: float, hi: float, nd: int = 3) -> float:
    return round(float(rng.uniform(lo, hi)), nd)


def _regular(rng: np.random.Generator) -> RoomSpec:
    n = int(rng.integers(3, 13))
    return RoomSpec("regular", n=n, gv=_u(rng, 1.5, 8.0), yaw_deg=_u(rng, 0.0, 360.0 / n, 2))


def _circle(rng: np.random.Generator) -> RoomSpec:
    return RoomSpec("circle", radius=_u(rng, 1.5, 8.0))


def _rectangle(rng: np.random.Generator) -> RoomSpec:
    aspect = float(rng.uniform(1.05, 3.0))
    gv = float(rng.uniform(max(1.5, 0.6 * math.hypot(aspect, 1.0)), 8.0))
    d = 2 * gv / math.hypot(aspect, 1.0)
    return RoomSpec(
        "rectangle",
        width=round(aspect * d, 3),
        depth=round(d, 3),
        yaw_deg=_u(rng, 0.0, 180.0, 2),
    )


def _rhombus(rng: np.random.Generator) -> RoomSpec:
    s = float(rng.uniform(2.0, 8.0))
    alpha = math.radians(float(rng.uniform(45.0, 85.0)))
    v = np.array(
        [
            [0.0, 0.0],
            [s, 0.0],
            [s + s * math.cos(alpha), s * math.sin(alpha)],
            [s * math.cos(alpha), s * math.sin(alpha)],
        ]
    )
    return _poly(_rotate(v, float(rng.uniform(0, math.pi))))


def _kite(rng: np.random.Generator) -> RoomSpec:
    a = float(rng.uniform(1.5, 6.0))
    b = a * float(rng.uniform(0.35, 0.8))
    w = float(rng.uniform(1.2, 5.0))
    v = np.array([[0.0, -a], [w, 0.0], [0.0, b], [-w, 0.0]])
    return _poly(_rotate(v, float(rng.uniform(0, 2 * math.pi))))


def _trapezoid(rng: np.random.Generator) -> RoomSpec:
    bottom = float(rng.uniform(3.0, 10.0))
    top = bottom * float(rng.uniform(0.3, 0.85))
    height = float(rng.uniform(2.0, 8.0))
    shift = float(rng.uniform(-0.5, 0.5)) * (bottom - top)
    x0 = (bottom - top) / 2 + shift
    v = np.array([[0.0, 0.0], [bottom, 0.0], [x0 + top, height], [x0, height]])
    return _poly(_rotate(v, float(rng.uniform(0, 2 * math.pi))))


def _convex(rng: np.random.Generator) -> RoomSpec:
    for _ in range(100):
        m = int(rng.integers(5, 10))
        ang = np.sort(rng.uniform(0, 2 * math.pi, m))
        rad = rng.uniform(2.0, 6.0, m)
        pts = np.column_stack([rad * np.cos(ang), rad * np.sin(ang)])
        hull = pts[ConvexHull(pts).vertices]
        edges = np.hypot(*(np.roll(hull, -1, axis=0) - hull).T)
        if hull.shape[0] >= 4 and edges.min() >= 1.0:
            return _poly(hull)
    raise WorldError("convex family: could not draw a room (this is a bug)")


def _l_shape(rng: np.random.Generator) -> RoomSpec:
    w = float(rng.uniform(3.5, 12.0))
    d = float(rng.uniform(3.5, 12.0))
    a = float(rng.uniform(1.4, 0.7 * w))
    b = float(rng.uniform(1.4, 0.7 * d))
    v = np.array([[0, 0], [w, 0], [w, b], [a, b], [a, d], [0, d]], dtype=np.float64)
    return _poly(_rotate(v, float(rng.uniform(0, 2 * math.pi))))


def _t_shape(rng: np.random.Generator) -> RoomSpec:
    w = float(rng.uniform(4.0, 12.0))
    bar = float(rng.uniform(1.4, 3.5))
    stem = float(rng.uniform(1.4, 0.5 * w))
    length = float(rng.uniform(1.5, 6.0))
    x0 = (w - stem) / 2 + float(rng.uniform(-0.3, 0.3)) * (w - stem)
    v = np.array(
        [
            [x0, 0],
            [x0 + stem, 0],
            [x0 + stem, length],
            [w, length],
            [w, length + bar],
            [0, length + bar],
            [0, length],
            [x0, length],
        ],
        dtype=np.float64,
    )
    return _poly(_rotate(v, float(rng.uniform(0, 2 * math.pi))))


def _u_shape(rng: np.random.Generator) -> RoomSpec:
    w = float(rng.uniform(4.5, 12.0))
    d = float(rng.uniform(3.5, 10.0))
    arm = float(rng.uniform(1.4, 0.35 * w))
    base = float(rng.uniform(1.4, 0.6 * d))
    v = np.array(
        [[0, 0], [w, 0], [w, d], [w - arm, d], [w - arm, base], [arm, base], [arm, d], [0, d]],
        dtype=np.float64,
    )
    return _poly(_rotate(v, float(rng.uniform(0, 2 * math.pi))))


def _cross(rng: np.random.Generator) -> RoomSpec:
    w = float(rng.uniform(1.4, 3.0))
    arm = float(rng.uniform(1.5, 5.0))
    h = w / 2
    e = h + arm
    v = np.array(
        [
            [h, -h],
            [e, -h],
            [e, h],
            [h, h],
            [h, e],
            [-h, e],
            [-h, h],
            [-e, h],
            [-e, -h],
            [-h, -h],
            [-h, -e],
            [h, -e],
        ]
    )
    return _poly(_rotate(v, float(rng.uniform(0, math.pi / 2))))


def _corridor(lo: float, hi: float) -> Callable[[np.random.Generator], RoomSpec]:
    def draw(rng: np.random.Generator) -> RoomSpec:
        return RoomSpec(
            "corridor",
            length=_u(rng, lo, hi),
            width=_u(rng, 1.2, 3.0),
            yaw_deg=_u(rng, 0.0, 180.0, 2),
        )

    return draw


def _family(
    name: str,
    description: str,
    symmetric: bool,
    params: dict[str, tuple[float, float]],
    draw: Callable[[np.random.Generator], RoomSpec],
    tall_only: bool = False,
) -> Family:
    return Family(name, description, symmetric, MappingProxyType(params), draw, tall_only)


_FURNISHED = Family(
    "furnished",
    "regular 3-8-gon, square, rectangle or circle (2.5-6 m) with 1-3 pieces of furniture (box,"
    " table legs, shelf on a wall; 12 % below the lidar plane) or a pillar grid or ring with one"
    " pillar missing or moved: nearly symmetric, the map overlaps itself by"
    f" {100 * furnished.MIN_OVERLAP:.0f}-100 % under the base rotation; order mostly 1",
    False,
    MappingProxyType(furnished.PARAMS),
    furnished.draw_base,
    furnish=furnished.furnish,
    # only what leaves the lidar's static geometry, so the recorded overlap stays true
    perturbations=("glass", "people", "aliasing", "dark"),
    nearly_symmetric=True,
)


FAMILIES: Mapping[str, Family] = MappingProxyType(
    {
        f.name: f
        for f in (
            _family(
                "regular",
                "regular n-gon (n = 3..12), centre to vertex 1.5-8 m, any yaw; order n",
                True,
                {"n": (3, 12), "gv_m": (1.5, 8.0)},
                _regular,
            ),
            _family(
                "circle",
                "round room of radius 1.5-8 m; continuous symmetry (order 0)",
                True,
                {"radius_m": (1.5, 8.0)},
                _circle,
            ),
            _family(
                "rectangle",
                "rectangle of aspect 1.05-3, half-diagonal 1.5-8 m, sides >= 1.2 m; order 2",
                True,
                {"aspect": (1.05, 3.0), "half_diagonal_m": (1.5, 8.0)},
                _rectangle,
            ),
            _family(
                "rhombus",
                "rhombus of side 2-8 m and acute angle 45-85 deg; order 2",
                True,
                {"side_m": (2.0, 8.0), "angle_deg": (45.0, 85.0)},
                _rhombus,
            ),
            _family(
                "kite",
                "kite (mirror symmetric only): half-diagonals 1.5-6 m and 0.35-0.8 of it, half-width 1.2-5 m; order 1",
                False,
                {"tip_m": (1.5, 6.0), "ratio": (0.35, 0.8), "half_width_m": (1.2, 5.0)},
                _kite,
            ),
            _family(
                "trapezoid",
                "trapezoid: base 3-10 m, top 0.3-0.85 of it, height 2-8 m, top shifted; order 1",
                False,
                {"base_m": (3.0, 10.0), "top_ratio": (0.3, 0.85), "height_m": (2.0, 8.0)},
                _trapezoid,
            ),
            _family(
                "convex",
                "irregular convex room: hull of 5-9 random points at 2-6 m, edges >= 1 m; order 1",
                False,
                {"vertices": (5, 9), "radius_m": (2.0, 6.0)},
                _convex,
            ),
            _family(
                "l_shape",
                "L-shaped room 3.5-12 m x 3.5-12 m, legs >= 1.4 m wide; order 1",
                False,
                {"size_m": (3.5, 12.0), "leg_m": (1.4, 8.4)},
                _l_shape,
            ),
            _family(
                "t_shape",
                "T-shaped room: bar 4-12 m x 1.4-3.5 m, stem 1.4 m-half the bar wide, 1.5-6 m long; order 1",
                False,
                {"bar_m": (4.0, 12.0), "bar_depth_m": (1.4, 3.5), "stem_length_m": (1.5, 6.0)},
                _t_shape,
            ),
            _family(
                "u_shape",
                "U-shaped room 4.5-12 m x 3.5-10 m, arms >= 1.4 m; order 1",
                False,
                {"width_m": (4.5, 12.0), "depth_m": (3.5, 10.0), "arm_m": (1.4, 4.2)},
                _u_shape,
            ),
            _family(
                "cross",
                "plus-shaped room: four equal arms 1.5-5 m long, 1.4-3 m wide; order 4",
                True,
                {"arm_m": (1.5, 5.0), "width_m": (1.4, 3.0)},
                _cross,
            ),
            _family(
                "corridor_short",
                f"corridor 6-28 m x 1.2-3 m: both ends within a {LIDAR_RANGE:g} m lidar's range from the middle; order 2",
                True,
                {"length_m": (6.0, 28.0), "width_m": (1.2, 3.0)},
                _corridor(6.0, 28.0),
                tall_only=True,
            ),
            _family(
                "corridor_long",
                f"corridor 40-60 m x 1.2-3 m: ends beyond a {LIDAR_RANGE:g} m lidar's range from the middle; order 2",
                True,
                {"length_m": (40.0, 60.0), "width_m": (1.2, 3.0)},
                _corridor(40.0, 60.0),
                tall_only=True,
            ),
            _FURNISHED,
        )
    }
)
"""The families by name."""


# --------------------------------------------------------------------------------------------
# perturbations
# --------------------------------------------------------------------------------------------


def _n_walls(spec: WorldSpec) -> int:
    r = spec.room
    if r.shape == "polygon":
        return len(r.polygon)
    if r.shape == "regular":
        return r.n
    return 0 if r.shape == "circle" else 4


def _free_points(room: Room, rng: np.random.Generator, n: int, clearance: float) -> FloatArray:
    xmin, ymin = room.boundary.min(axis=0)
    xmax, ymax = room.boundary.max(axis=0)
    out: list[FloatArray] = []
    for _ in range(50):
        cand = np.column_stack([rng.uniform(xmin, xmax, 128), rng.uniform(ymin, ymax, 128)])
        cand = cand[room.is_free(cand, clearance)]
        out.extend(cand[: n - len(out)])
        if len(out) >= n:
            break
    return np.array(out).reshape(-1, 2)


def _item(
    rng: np.random.Generator, center: FloatArray, high: bool, scale: float = 1.0
) -> FurnitureSpec:
    height = _u(rng, 0.5, 1.2) if high else _u(rng, 0.1, 0.25)
    c = (round(float(center[0]), 3), round(float(center[1]), 3))
    if rng.random() < 0.6:
        size = (_u(rng, 0.3, 0.9) * scale, _u(rng, 0.3, 0.9) * scale)
        return FurnitureSpec("box", c, size=size, yaw_deg=_u(rng, 0, 180, 1), height=height)
    return FurnitureSpec("cylinder", c, radius=_u(rng, 0.15, 0.4) * scale, height=height)


def _extent(f: FurnitureSpec) -> float:
    return math.hypot(*f.size) / 2 if f.kind == "box" else f.radius


def _far_from_centre(room: Room, pts: FloatArray, reach: float) -> FloatArray:
    return np.asarray(
        pts[np.hypot(*(pts - room.center).T) >= _CENTRE_FREE + reach], dtype=np.float64
    )


def _furniture(spec: WorldSpec, room: Room, rng: np.random.Generator, tags: list[str]) -> WorldSpec:
    high = bool(rng.random() < 0.6)
    count = int(rng.integers(1, 4))
    items = list(spec.furniture)
    for _ in range(count):
        f0 = _item(rng, np.zeros(2), high)
        pts = _far_from_centre(room, _free_points(room, rng, 20, _extent(f0) + 0.1), _extent(f0))
        for p in pts:
            f = replace(f0, center=(round(float(p[0]), 3), round(float(p[1]), 3)))
            if all(_apart(f, g, ROBOT_RADIUS * 2 + 0.05) for g in (*items, *spec.pillars)):
                items.append(f)
                break
    placed = len(items) - len(spec.furniture)
    if placed:
        where = "above" if high else "below"
        tags.append(f"furniture({placed} {where} the lidar plane)")
    return replace(spec, furniture=tuple(items))


def _apart(a: FurnitureSpec, b: FurnitureSpec, gap: float) -> bool:
    d = math.hypot(a.center[0] - b.center[0], a.center[1] - b.center[1])
    return d >= _extent(a) + _extent(b) + gap


def _symmetric_furniture(
    spec: WorldSpec, room: Room, rng: np.random.Generator, tags: list[str]
) -> WorldSpec:
    k = room.order if room.order >= 2 else (4 if room.order == 0 else 0)
    if k == 0 or k > 8:
        return spec
    f0 = _item(rng, np.zeros(2), bool(rng.random() < 0.7), scale=0.7)
    reach = _extent(f0)
    pts = _far_from_centre(room, _free_points(room, rng, 30, reach + 0.1), reach + 0.3)
    c = room.center
    for p in pts:
        ang0 = math.atan2(p[1] - c[1], p[0] - c[0])
        rad = float(np.hypot(*(p - c)))
        copies = []
        for j in range(k):
            a = ang0 + 2 * math.pi * j / k
            q = (
                round(float(c[0] + rad * math.cos(a)), 6),
                round(float(c[1] + rad * math.sin(a)), 6),
            )
            yaw = f0.yaw_deg + math.degrees(a - ang0)
            copies.append(replace(f0, center=q, yaw_deg=round(yaw % 360.0, 6)))
        if not np.all(room.is_free(np.array([g.center for g in copies]), _extent(f0) + 0.05)):
            continue
        if all(
            _apart(a, b, 2 * ROBOT_RADIUS + 0.05) for i, a in enumerate(copies) for b in copies[:i]
        ):
            tags.append(f"symmetric_furniture({k} copies)")
            return replace(spec, furniture=(*spec.furniture, *copies))
    return spec


def _chamfer(spec: WorldSpec, rng: np.random.Generator, tags: list[str]) -> WorldSpec:
    n = _n_walls(spec)
    if n == 0:
        return spec
    lengths = _edge_lengths(spec)
    top = min(0.5, 0.4 * float(min(lengths)))
    if top < 0.05:
        return spec
    c: tuple[float, ...]
    if rng.random() < 0.5:
        c = (_u(rng, 0.05, top),)
        tags.append(f"chamfer(equal {c[0]} m)")
    else:
        c = tuple(_u(rng, 0.05, top) for _ in range(n))
        tags.append("chamfer(unequal)")
    return replace(spec, room=replace(spec.room, chamfer=c))


def _edge_lengths(spec: WorldSpec) -> list[float]:
    v = corner_points(spec.room)
    return [float(x) for x in np.hypot(*(np.roll(v, -1, axis=0) - v).T)]


def _door(spec: WorldSpec, rng: np.random.Generator, tags: list[str]) -> WorldSpec:
    is_open = bool(rng.random() < 0.7)
    width = _u(rng, 0.8, 1.0)
    if spec.room.shape == "circle":
        door = DoorSpec(wall=0, at=_u(rng, 0.0, 1.0), width=width, open=is_open)
    else:
        lengths = _edge_lengths(spec)
        cut = max(spec.room.chamfer, default=0.0)
        ok = [i for i, length in enumerate(lengths) if length - 2 * cut >= width + 0.4]
        if not ok:
            return spec
        wall = int(rng.choice(ok))
        length = lengths[wall]
        margin = (cut + width / 2 + 0.1) / length
        door = DoorSpec(wall=wall, at=_u(rng, margin, 1 - margin), width=width, open=is_open)
    tags.append(f"door({'open' if is_open else 'closed'})")
    return replace(spec, doors=(*spec.doors, door))


def _pillars(spec: WorldSpec, room: Room, rng: np.random.Generator, tags: list[str]) -> WorldSpec:
    count = int(rng.integers(1, 3))
    items = list(spec.pillars)
    for _ in range(count):
        if rng.random() < 0.5:
            p0 = FurnitureSpec(
                "cylinder", (0.0, 0.0), radius=_u(rng, 0.1, 0.3), height=2.5, material="plain"
            )
        else:
            s = _u(rng, 0.2, 0.5)
            p0 = FurnitureSpec(
                "box",
                (0.0, 0.0),
                size=(s, s),
                yaw_deg=_u(rng, 0, 90, 1),
                height=2.5,
                material="plain",
            )
        pts = _far_from_centre(room, _free_points(room, rng, 20, _extent(p0) + 0.1), _extent(p0))
        for p in pts:
            f = replace(p0, center=(round(float(p[0]), 3), round(float(p[1]), 3)))
            if all(_apart(f, g, 2 * ROBOT_RADIUS + 0.05) for g in (*items, *spec.furniture)):
                items.append(f)
                break
    if len(items) > len(spec.pillars):
        tags.append(f"pillars({len(items) - len(spec.pillars)})")
    return replace(spec, pillars=tuple(items))


def _glass(spec: WorldSpec, room: Room, rng: np.random.Generator, tags: list[str]) -> WorldSpec:
    length = _u(rng, 0.8, 2.0)
    for p in _far_from_centre(room, _free_points(room, rng, 30, length / 2 + 0.1), length / 2):
        a = float(rng.uniform(0, math.pi))
        d = np.array([math.cos(a), math.sin(a)]) * length / 2
        s, e = p - d, p + d
        line = s + np.linspace(0, 1, 20)[:, None] * (e - s)
        if not np.all(room.is_free(line, 0.1)):
            continue
        far = [
            _dist_to_segment(np.array(f.center), s, e) >= _extent(f) + 2 * ROBOT_RADIUS
            for f in (*spec.furniture, *spec.pillars)
        ]
        if all(far):
            g = GlassSpec(
                (round(float(s[0]), 3), round(float(s[1]), 3)),
                (round(float(e[0]), 3), round(float(e[1]), 3)),
            )
            tags.append("glass(1 panel)")
            return replace(spec, glass=(*spec.glass, g))
    return spec


def _dist_to_segment(p: FloatArray, a: FloatArray, b: FloatArray) -> float:
    ab = b - a
    t = min(1.0, max(0.0, float((p - a) @ ab) / float(ab @ ab)))
    return float(np.hypot(*(p - a - t * ab)))


def _people(spec: WorldSpec, room: Room, rng: np.random.Generator, tags: list[str]) -> WorldSpec:
    count = int(rng.integers(1, 4))
    people: list[PersonSpec] = []
    for _ in range(count):
        radius = _u(rng, 0.2, 0.3)
        for _attempt in range(20):
            m = int(rng.integers(2, 5))
            pts = _free_points(room, rng, m, radius + 0.05)
            if pts.shape[0] < m:
                break
            legs = [(pts[i], pts[i + 1]) for i in range(m - 1)]
            if any(float(np.hypot(*(b - a))) < 1.0 for a, b in legs):
                continue
            ok = all(
                np.all(
                    room.is_free(
                        a
                        + np.linspace(0, 1, max(2, math.ceil(float(np.hypot(*(b - a))) / 0.04)))[
                            :, None
                        ]
                        * (b - a),
                        radius + 0.02,
                    )
                )
                for a, b in legs
            )
            if ok:
                path = tuple((round(float(x), 3), round(float(y), 3)) for x, y in pts)
                total = sum(float(np.hypot(*(b - a))) for a, b in legs)
                people.append(
                    PersonSpec(
                        path, speed=_u(rng, 0.8, 1.3), radius=radius, phase=_u(rng, 0.0, total)
                    )
                )
                break
    if people:
        tags.append(f"people({len(people)} walking)")
    return replace(spec, people=(*spec.people, *people))


def _wall_count(spec: WorldSpec, room: Room) -> int:
    if spec.room.in_lab:
        return 12
    if spec.room.shape == "circle":
        return max(4, round(2 * math.pi * spec.room.radius / spec.room.wall_height))
    return _n_walls(spec)


def _aliasing(spec: WorldSpec, room: Room, rng: np.random.Generator, tags: list[str]) -> WorldSpec:
    n = _wall_count(spec, room)
    ids = [int(k) for k in rng.choice(TEXTURE_POOL, size=n, replace=False)]
    i, j = (int(x) for x in rng.choice(n, size=2, replace=False))
    ids[j] = ids[i]
    tags.append(f"aliasing(walls {i} and {j} show texture {ids[i]})")
    return replace(spec, lab=replace(spec.lab, textures=tuple(ids), textured=True))


def _dark(spec: WorldSpec, room: Room, rng: np.random.Generator, tags: list[str]) -> WorldSpec:
    if spec.room.in_lab:
        return spec
    n = _wall_count(spec, room)
    textures: list[int | str] = list(spec.lab.textures) or [
        int(k) for k in rng.choice(TEXTURE_POOL, size=n, replace=False)
    ]
    w = int(rng.integers(n))
    textures[w] = "dark"
    tags.append(f"dark(wall {w})")
    return replace(spec, lab=replace(spec.lab, textures=tuple(textures)))


# --------------------------------------------------------------------------------------------
# the generator
# --------------------------------------------------------------------------------------------


def _rng(family: str, seed: int, salt: int) -> np.random.Generator:
    return np.random.default_rng([zlib.crc32(family.encode()), int(seed), salt])


def _valid(room: Room, symmetric: bool) -> bool:
    """A robot fits; in a symmetric room it stands at the centre and reaches most of the room."""
    fs = room.free_space(ROBOT_RADIUS)
    if fs.reachable_label == 0:
        return False
    if symmetric:
        if not bool(room.is_free(room.center[None], ROBOT_RADIUS)[0]):
            return False
        return fs.reachable_area >= 0.9 * fs.free_area
    return fs.reachable_area >= 0.5 * fs.free_area


def generate_world(family: str, seed: int, *, perturb: bool | None = None) -> WorldSpec:
    """Draw a world of ``family`` deterministically from ``seed``.

    Parameters
    ----------
    family : str
        A key of :data:`FAMILIES`.
    seed : int
        >= 0; the same (family, seed, perturb) always gives the same world.
    perturb : bool or None
        True: one to three perturbations (see the module docstring); False: the bare family
        room; None: the seed decides (half of the seeds are perturbed).

    Returns
    -------
    WorldSpec
        Valid (see the module docstring); ``seed`` is also the world's texture seed and
        ``generator`` records (family, seed).
    """
    if family not in FAMILIES:
        raise ConfigurationError(
            f"generate_world: unknown family {family!r}; expected one of {', '.join(FAMILIES)}"
        )
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigurationError(f"generate_world: seed must be an integer >= 0, got {seed!r}")
    fam = FAMILIES[family]
    rng = _rng(family, int(seed), 0)
    do_perturb = bool(rng.random() < 0.5) if perturb is None else bool(perturb)
    for attempt in range(_ATTEMPTS):
        shape = fam.draw(rng)
        boards = not fam.tall_only and rng.random() < 0.3
        height = _u(rng, BOARD_HEIGHT, 0.6, 2) if boards else _u(rng, 2.0, 3.0, 2)
        room_spec = replace(shape, wall_height=height)
        tags: list[str] = []
        try:
            spec = WorldSpec(
                name=f"{family}-{seed}",
                room=room_spec,
                lab=LabSpec(textured=True),
                seed=int(seed),
                generator=(family, int(seed)),
                source=f"generate_world({family!r}, {seed})",
            )
            if fam.furnish is not None:
                spec = fam.furnish(spec, rng)
            if do_perturb:
                spec = _perturb(spec, rng, tags, fam.perturbations)
            room = spec.build()
        except WorldError:
            if attempt == _ATTEMPTS - 1:
                raise
            continue
        if not _valid(room, room.symmetric or fam.nearly_symmetric):
            continue
        what = _describe(fam, spec)
        pert = "; perturbed: " + ", ".join(tags) if tags else ""
        return replace(spec, description=f"{what}{pert}")
    raise WorldError(
        f"generate_world: no valid {family} world after {_ATTEMPTS} draws for seed {seed}"
    )


def _perturb(
    spec: WorldSpec,
    rng: np.random.Generator,
    tags: list[str],
    allowed: tuple[str, ...] = PERTURBATIONS,
) -> WorldSpec:
    """Apply one to three perturbations of ``allowed`` (at least one that takes, when any can)."""
    count = int(rng.integers(1, min(4, len(allowed) + 1)))
    kinds = [str(k) for k in rng.permutation(allowed)]
    chosen = kinds[:count]
    # geometry of the room first (corner cuts, doors), then what stands in it
    rank = {k: i for i, k in enumerate(PERTURBATIONS)}
    chosen.sort(key=lambda k: (k not in ("chamfer", "door"), rank[k]))
    for kind in [*chosen, *kinds[count:]]:
        if kind not in chosen and tags:
            break  # the spares only stand in when none of the chosen ones applied
        spec = _apply(kind, spec, rng, tags)
    return spec


def _apply(kind: str, spec: WorldSpec, rng: np.random.Generator, tags: list[str]) -> WorldSpec:
    if kind == "chamfer":
        return _chamfer(spec, rng, tags)
    if kind == "door":
        return _door(spec, rng, tags)
    step: dict[str, Any] = {
        "furniture": _furniture,
        "symmetric_furniture": _symmetric_furniture,
        "pillars": _pillars,
        "glass": _glass,
        "people": _people,
        "aliasing": _aliasing,
        "dark": _dark,
    }
    # only symmetric furniture needs the order; the rest need the outline and free space
    room = spec.build() if kind == "symmetric_furniture" else assemble(spec)
    result: WorldSpec = step[kind](spec, room, rng, tags)
    return result


def _describe(fam: Family, spec: WorldSpec) -> str:
    r = spec.room
    where = "boards in a lab" if r.in_lab else "tall walls"
    if r.shape == "regular":
        geo = f"regular {r.n}-gon, G-V {r.gv} m"
    elif r.shape == "circle":
        geo = f"circle, radius {r.radius} m"
    elif r.shape == "rectangle":
        geo = f"rectangle {r.width} m x {r.depth} m"
    elif r.shape == "corridor":
        geo = f"corridor {r.length} m x {r.width} m"
    else:
        geo = f"{fam.name} polygon, {len(r.polygon)} corners"
    text = f"{geo}, {where} {r.wall_height} m high"
    meta = spec.meta
    if "overlap" in meta:
        text += (
            f"; furnished: {meta['pieces']} (base order {meta['base_order']}, overlap"
            f" {100 * float(meta['overlap']):.1f} % at {meta['overlap_turn_deg']} deg)"
        )
    return text
