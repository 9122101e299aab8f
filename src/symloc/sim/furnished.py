"""Furnished symmetric rooms: the ``furnished`` generator family.

The rooms the paper describes ("most of them are symmetrical before placing furniture"): a
symmetric base room of bench size, then a few pieces that break its symmetry only a little, so
that the lidar leaves rival poses (the map overlaps itself by 85-100 % under the base rotation).

Base rooms (:func:`draw_base`): a regular n-gon (n = 3..8, centre to vertex 2.5-6 m, 3-6 m for
a triangle; 45 % of the worlds), a square (half-diagonal 2.5-6 m; 15 %), a rectangle (aspect
1.2-2.5, half-diagonal 2.5-6 m; 20 %) or a circle (radius 2.5-6 m; 20 %).

Layouts (:func:`furnish`, drawn per world):

``furniture`` (55 %)
    one to three pieces taller than the lidar plane: a box (0.3-0.9 m x 0.3-0.9 m, 0.5-1.2 m
    high), a table (four legs of radius 2.5-4 cm at the corners of 0.8-1.6 m x 0.6-1 m, 0.72-0.76
    m high: the lidar sees the legs only) or a shelf against a wall (0.8-2 m long, 0.3-0.45 m
    deep, 1.2-2 m high, 3-6 cm off the wall);
``low_furniture`` (15 %)
    one to three boxes or wall benches of the same footprints but 0.1-0.25 m high: below the
    lidar plane, so exactly symmetric for the lidar and not for the camera;
``pillars`` (30 %)
    floor-to-ceiling pillars (round, radius 0.1-0.25 m, or square, 0.2-0.45 m) centred on the
    room: a grid (2 x 2, 2 x 3, or 3 x 3 without its centre pillar, so the centre stays free)
    in rooms whose order shares a factor with the grid's (squares, rectangles, 4-, 6- and
    8-gons, circles), else a ring of n pillars in an n-gon; then one pillar removed (40 %),
    one moved by 0.2-0.6 m (40 %) or none (20 %: the room stays exactly symmetric).

Every world records in :attr:`~symloc.sim.world_file.WorldSpec.metadata`:

``base_shape``
    ``regular 5-gon``, ``square``, ``rectangle`` or ``circle``;
``layout``, ``pieces``
    the layout and what was placed (``box, table``; ``3x3 grid without its centre, one
    moved``);
``base_order``
    the order of the symmetric room before the symmetry was broken, computed from the geometry
    (:func:`~symloc.sim.symmetry_truth.lidar_symmetry`): the bare room's for furniture (0 for a
    circle), the room with the intact pillar layout's for pillars;
``overlap``, ``overlap_turn_deg``
    the share of the room's lidar-visible map that lies on itself turned by 360 / base order
    degrees (a half turn for a circle), as the localizer measures it
    (:func:`~symloc.sim.symmetry_truth.near_symmetry_overlap`); at least :data:`MIN_OVERLAP`,
    1.0 for low furniture and intact pillars.

Placement keeps the room usable: every piece is at least 0.6 m plus its size from the centre,
free-standing pieces leave a robot's passage (2 x 0.18 m + 5 cm) to the walls and to each
other, the centre is free and at least 97 % of the free space is reachable from it. The true
order of the result is computed when the world is built, as for every family: 1 when the
furniture breaks the symmetry, the base order when the lidar cannot see it.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from symloc.errors import WorldError
from symloc.sim.rooms import ROBOT_RADIUS, Room
from symloc.sim.symmetry_truth import near_symmetry_overlap
from symloc.sim.world_build import assemble
from symloc.sim.world_file import MetaValue, WorldSpec
from symloc.sim.world_spec import PILLAR_HEIGHT, FurnitureSpec, RoomSpec

__all__ = ["LAYOUTS", "MIN_OVERLAP", "PARAMS", "draw_base", "furnish"]

FloatArray = NDArray[np.float64]

LAYOUTS = ("furniture", "low_furniture", "pillars")
"""The layouts (see the module docstring)."""
MIN_OVERLAP = 0.85
"""A furnishing whose map overlaps itself less than this under the base rotation is drawn
again: the family is about rooms that stay nearly symmetric."""
PARAMS: dict[str, tuple[float, float]] = {
    "n": (3, 8),
    "gv_m": (2.5, 6.0),
    "aspect": (1.2, 2.5),
    "pieces": (1, 3),
    "pillars": (3, 8),
    "overlap": (MIN_OVERLAP, 1.0),
}
"""Parameter ranges (the family's ``params``)."""

_PASSAGE = 2 * ROBOT_RADIUS + 0.05  # a robot drives between two pieces, or a piece and a wall
_CENTRE_FREE = 0.6  # keep this much [m] (plus the piece) clear round the centre
_ATTEMPTS = 12
_REACHABLE = 0.97


def _u(rng: np.random.Generator, lo: float, hi: float, nd: int = 3) -> float:
    return round(float(rng.uniform(lo, hi)), nd)


def _pt(p: FloatArray) -> tuple[float, float]:
    return (round(float(p[0]), 3), round(float(p[1]), 3))


def _unit(angle: float) -> FloatArray:
    return np.array([math.cos(angle), math.sin(angle)])


# --------------------------------------------------------------------------------------------
# base rooms
# --------------------------------------------------------------------------------------------


def draw_base(rng: np.random.Generator) -> RoomSpec:
    """A symmetric base room of bench size (see the module docstring); shape only."""
    r = float(rng.random())
    if r < 0.45:
        n = int(rng.integers(3, 9))
        gv = _u(rng, 3.0 if n == 3 else 2.5, 6.0)
        return RoomSpec("regular", n=n, gv=gv, yaw_deg=_u(rng, 0.0, 360.0 / n, 2))
    if r < 0.6:
        side = round(_u(rng, 2.5, 6.0) * math.sqrt(2.0), 3)
        return RoomSpec("rectangle", width=side, depth=side, yaw_deg=_u(rng, 0.0, 90.0, 2))
    if r < 0.8:
        aspect = float(rng.uniform(1.2, 2.5))
        gv = float(rng.uniform(max(2.5, 1.6 * math.hypot(aspect, 1.0) / 2.0), 6.0))
        d = 2 * gv / math.hypot(aspect, 1.0)
        return RoomSpec(
            "rectangle",
            width=round(aspect * d, 3),
            depth=round(d, 3),
            yaw_deg=_u(rng, 0.0, 180.0, 2),
        )
    return RoomSpec("circle", radius=_u(rng, 2.5, 6.0))


def base_name(room: RoomSpec) -> str:
    """``regular 5-gon``, ``square``, ``rectangle`` or ``circle``."""
    if room.shape == "regular":
        return f"regular {room.n}-gon"
    if room.shape == "rectangle":
        return "square" if room.width == room.depth else "rectangle"
    return room.shape


# --------------------------------------------------------------------------------------------
# pieces
# --------------------------------------------------------------------------------------------


def _extent(f: FurnitureSpec) -> float:
    return math.hypot(*f.size) / 2 if f.kind == "box" else f.radius


def _box(rng: np.random.Generator, low: bool) -> list[FurnitureSpec]:
    height = _u(rng, 0.1, 0.25) if low else _u(rng, 0.5, 1.2)
    size = (_u(rng, 0.2, 0.9), _u(rng, 0.2, 0.9))
    return [FurnitureSpec("box", (0.0, 0.0), size=size, yaw_deg=_u(rng, 0, 180, 1), height=height)]


def _table(rng: np.random.Generator) -> list[FurnitureSpec]:
    a, b = _u(rng, 0.8, 1.6), _u(rng, 0.6, 1.0)
    r, h = _u(rng, 0.025, 0.04), _u(rng, 0.72, 0.76)
    return [
        FurnitureSpec("cylinder", (sx * (a / 2 - r), sy * (b / 2 - r)), radius=r, height=h)
        for sx in (-1, 1)
        for sy in (-1, 1)
    ]


def _placed(parts: list[FurnitureSpec], at: FloatArray, yaw: float) -> tuple[FurnitureSpec, ...]:
    """``parts`` (laid out round the origin, yaw 0) turned by ``yaw`` [rad] and moved to ``at``."""
    c, s = math.cos(yaw), math.sin(yaw)
    out = []
    for f in parts:
        x, y = f.center
        p = at + np.array([c * x - s * y, s * x + c * y])
        turned = round((f.yaw_deg + math.degrees(yaw)) % 360, 3) if f.kind == "box" else 0.0
        out.append(replace(f, center=_pt(p), yaw_deg=turned))
    return tuple(out)


def _reach(parts: tuple[FurnitureSpec, ...], at: FloatArray) -> float:
    """Radius [m] round ``at`` that holds every part."""
    return max(math.dist(f.center, at) + _extent(f) for f in parts)


def _wall_spots(
    room: Room, rng: np.random.Generator, length: float
) -> list[tuple[FloatArray, FloatArray, float]]:
    """Points on the walls where a piece ``length`` [m] long can stand, with the inward normal
    and the extra offset a curved wall needs (its sagitta), in random order."""
    b = room.boundary
    spots: list[tuple[FloatArray, FloatArray, float]] = []
    if room.kind == "circle":
        radius = float(np.max(np.hypot(*(b - room.center).T)))
        if length >= 2 * radius - 1.0:
            return []
        sagitta = radius - math.sqrt(radius**2 - (length / 2) ** 2)
        for phi in rng.uniform(0, 2 * math.pi, 8):
            u = _unit(float(phi))
            spots.append((room.center + radius * u, -u, sagitta))
        return spots
    for i in rng.permutation(b.shape[0]):
        a, e = b[int(i)], b[(int(i) + 1) % b.shape[0]]
        edge = float(np.hypot(*(e - a)))
        margin = length / 2 + 0.5
        if edge < 2 * margin:
            continue
        t = float(rng.uniform(margin, edge - margin)) / edge
        d = (e - a) / edge
        normal = np.array([-d[1], d[0]])  # counter-clockwise outline: the inside is to the left
        spots.append((a + t * (e - a), normal, 0.0))
    return spots


def _shelf(rng: np.random.Generator, room: Room, low: bool) -> list[tuple[FurnitureSpec, ...]]:
    """Candidate placements of one shelf (or, ``low``, a bench) against a wall."""
    length, depth = _u(rng, 0.6, 2.0), _u(rng, 0.3, 0.45)
    height = _u(rng, 0.1, 0.25) if low else _u(rng, 1.2, 2.0)
    gap = _u(rng, 0.03, 0.06)
    out = []
    for wall_pt, normal, sagitta in _wall_spots(room, rng, length):
        at = wall_pt + normal * (gap + sagitta + depth / 2)
        yaw = math.atan2(normal[1], normal[0]) + math.pi / 2
        f = FurnitureSpec("box", (0.0, 0.0), size=(length, depth), height=height)
        out.append(_placed([f], at, yaw))
    return out


def _free_standing(
    rng: np.random.Generator, room: Room, parts: list[FurnitureSpec]
) -> list[tuple[FurnitureSpec, ...]]:
    """Candidate placements of a free-standing piece: a passage to every wall and piece."""
    reach = max(math.hypot(*f.center) + _extent(f) for f in parts)
    xmin, ymin = room.boundary.min(axis=0)
    xmax, ymax = room.boundary.max(axis=0)
    cand = np.column_stack([rng.uniform(xmin, xmax, 64), rng.uniform(ymin, ymax, 64)])
    cand = cand[np.hypot(*(cand - room.center).T) >= _CENTRE_FREE + ROBOT_RADIUS + reach]
    cand = cand[room.is_free(cand, reach + _PASSAGE)]
    return [_placed(parts, p, float(rng.uniform(0, 2 * math.pi))) for p in cand[:8]]


def _furniture(spec: WorldSpec, rng: np.random.Generator, low: bool) -> tuple[WorldSpec, list[str]]:
    count = int(rng.choice([1, 2, 3], p=[0.5, 0.3, 0.2]))
    names: list[str] = []
    for _ in range(count):
        room = assemble(spec)
        kind = str(rng.choice(["box", "shelf"] if low else ["box", "table", "shelf"]))
        if kind == "shelf":
            options = _shelf(rng, room, low)
        else:
            options = _free_standing(rng, room, _table(rng) if kind == "table" else _box(rng, low))
        for parts in options:
            at = np.mean([f.center for f in parts], axis=0)
            if math.dist(at, room.center) < _CENTRE_FREE + ROBOT_RADIUS + _reach(parts, at):
                continue
            if not _apart(parts, at, spec):
                continue
            try:
                nxt = replace(spec, furniture=(*spec.furniture, *parts))
                assemble(nxt)
            except WorldError:
                continue
            spec = nxt
            names.append("bench" if low and kind == "shelf" else kind)
            break
    return spec, names


def _apart(parts: tuple[FurnitureSpec, ...], at: FloatArray, spec: WorldSpec) -> bool:
    """A robot passes between the new piece (its bounding circle) and every other one."""
    r = _reach(parts, at)
    others = [*spec.furniture, *spec.pillars]
    return all(math.dist(at, g.center) >= r + _extent(g) + _PASSAGE for g in others)


# --------------------------------------------------------------------------------------------
# pillars
# --------------------------------------------------------------------------------------------


def _pillar_layout(
    spec: WorldSpec, room: Room, rng: np.random.Generator
) -> tuple[list[tuple[FloatArray, float]], str]:
    """Pillar positions centred on the room with the yaw [deg] of a square pillar there (one
    side along the grid's axis, or facing the centre in a ring), and the layout's name."""
    shape = spec.room
    c = room.center
    n = shape.n if shape.shape == "regular" else 0
    inner = float(np.min(np.hypot(*(room.boundary - c).T)))  # inradius (about)
    if n in (3, 5, 7):
        corner = room.boundary[0] - c
        a0 = math.atan2(corner[1], corner[0]) + (math.pi / n if rng.random() < 0.5 else 0.0)
        rho = float(rng.uniform(0.35, 0.65)) * inner
        angles = [a0 + 2 * math.pi * j / n for j in range(n)]
        return [(c + rho * _unit(a), math.degrees(a)) for a in angles], f"ring of {n}"
    axis = math.radians(shape.yaw_deg)
    if shape.shape == "regular":
        edge = room.boundary[1] - room.boundary[0]  # the grid runs along the walls
        axis = math.atan2(edge[1], edge[0])
    square_only = (shape.shape == "rectangle" and shape.width == shape.depth) or n in (4, 8)
    grid = str(rng.choice(["2x2", "3x3"] if square_only else ["2x2", "2x3", "3x3"]))
    s = float(rng.uniform(0.45, 0.8)) * inner
    t = s if square_only or shape.shape == "circle" else float(rng.uniform(0.45, 0.8)) * inner
    if shape.shape == "rectangle" and not square_only:
        # spread along the room's sides
        t = s * shape.depth / shape.width
    if grid == "2x2":
        local = [(sx * s / 2, sy * t / 2) for sx in (-1, 1) for sy in (-1, 1)]
        name = "2x2 grid"
    elif grid == "2x3":
        local = [(sx * s / 2, sy * t / 2) for sx in (-1, 1) for sy in (-1, 0, 1)]
        name = "2x3 grid"
    else:
        local = [(sx * s / 2, sy * t / 2) for sx in (-1, 0, 1) for sy in (-1, 0, 1) if sx or sy]
        name = "3x3 grid without its centre"
    ca, sa = math.cos(axis), math.sin(axis)
    yaw = math.degrees(axis)
    return [(c + np.array([ca * x - sa * y, sa * x + ca * y]), yaw) for x, y in local], name


def _pillars(spec: WorldSpec, rng: np.random.Generator) -> tuple[WorldSpec, WorldSpec, str]:
    """The room with an intact pillar layout, the same with its symmetry broken, the name."""
    room = assemble(spec)
    spots, name = _pillar_layout(spec, room, rng)
    if rng.random() < 0.5:
        p0 = FurnitureSpec(
            "cylinder",
            (0.0, 0.0),
            radius=_u(rng, 0.1, 0.25),
            height=PILLAR_HEIGHT,
            material="plain",
        )
    else:
        side = _u(rng, 0.2, 0.45)
        p0 = FurnitureSpec(
            "box",
            (0.0, 0.0),
            size=(side, side),
            yaw_deg=0.0,
            height=PILLAR_HEIGHT,
            material="plain",
        )
    pillars = [
        replace(p0, center=_pt(p), yaw_deg=round(yaw % 90.0, 3) if p0.kind == "box" else 0.0)
        for p, yaw in spots
    ]
    reach = _extent(p0)
    if any(math.dist(p.center, room.center) < _CENTRE_FREE + ROBOT_RADIUS + reach for p in pillars):
        raise WorldError("furnished: pillars too close to the centre")
    if not np.all(room.is_free(np.array([p.center for p in pillars]), reach + _PASSAGE)):
        raise WorldError("furnished: pillars too close to the walls")
    gaps = [math.dist(a.center, b.center) for i, a in enumerate(pillars) for b in pillars[:i]]
    if min(gaps) < 2 * reach + _PASSAGE:
        raise WorldError("furnished: pillars too close to each other")
    intact = replace(spec, pillars=tuple(pillars))
    r = float(rng.random())
    if r < 0.4:
        k = int(rng.integers(len(pillars)))
        broken = replace(spec, pillars=tuple(p for i, p in enumerate(pillars) if i != k))
        return intact, broken, f"{name}, one missing"
    if r < 0.85:
        k = int(rng.integers(len(pillars)))
        shift = _u(rng, 0.15, 0.6) * _unit(float(rng.uniform(0, 2 * math.pi)))
        moved = replace(pillars[k], center=_pt(np.array(pillars[k].center) + shift))
        rest = [p for i, p in enumerate(pillars) if i != k]
        if not room.is_free(np.array([moved.center]), reach + _PASSAGE)[0]:
            raise WorldError("furnished: moved pillar too close to a wall")
        if any(math.dist(moved.center, p.center) < 2 * reach + _PASSAGE for p in rest):
            raise WorldError("furnished: moved pillar too close to another")
        if math.dist(moved.center, room.center) < _CENTRE_FREE + ROBOT_RADIUS + reach:
            raise WorldError("furnished: moved pillar too close to the centre")
        pillars[k] = moved
        return (
            intact,
            replace(spec, pillars=tuple(pillars)),
            f"{name}, one moved {math.hypot(*shift):.2f} m",
        )
    return intact, intact, f"{name}, intact"


# --------------------------------------------------------------------------------------------
# the family's step
# --------------------------------------------------------------------------------------------


def _usable(room: Room) -> bool:
    """The centre is free and (nearly) all the free space is reachable from it."""
    if not bool(room.is_free(room.center[None], _CENTRE_FREE)[0]):
        return False
    fs = room.free_space(ROBOT_RADIUS)
    return fs.reachable_label != 0 and fs.reachable_area >= _REACHABLE * fs.free_area


def furnish(spec: WorldSpec, rng: np.random.Generator) -> WorldSpec:
    """Furnish a symmetric base room (see the module docstring); records the metadata.

    Raises :class:`~symloc.errors.WorldError` if no furnishing both fits and keeps the room
    nearly symmetric (the generator then draws another room).
    """
    bare = spec.build()
    if bare.order == 1:
        raise WorldError(f"furnished: the base room {spec.room.shape} is not symmetric")
    layout = str(rng.choice(LAYOUTS, p=[0.55, 0.12, 0.33]))
    for _ in range(_ATTEMPTS):
        try:
            if layout == "pillars":
                intact, out, pieces = _pillars(spec, rng)
                base_order = intact.build().order
                kind = "pillar_ring" if pieces.startswith("ring") else "pillar_grid"
            else:
                out, names = _furniture(spec, rng, low=layout == "low_furniture")
                if not names:
                    continue
                pieces = ", ".join(names)
                base_order = bare.order
                kind = layout
        except WorldError:
            continue
        if base_order == 1:
            continue
        room = assemble(out)
        if not _usable(room):
            continue
        k = base_order if base_order >= 2 else 2
        overlap = near_symmetry_overlap(room.world, room.boundary, k, bare.center)
        if overlap < MIN_OVERLAP:
            continue
        meta: dict[str, MetaValue] = {
            "base_shape": base_name(spec.room),
            "layout": kind,
            "pieces": pieces,
            "base_order": int(base_order),
            "overlap_turn_deg": round(360.0 / k, 3),
            "overlap": round(overlap, 4),
        }
        return replace(out, metadata=tuple(meta.items()))
    raise WorldError(
        f"furnished: no {layout} layout fits {spec.name} and keeps it nearly symmetric"
    )
