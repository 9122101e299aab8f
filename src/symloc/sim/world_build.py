"""World files, the geometry half: from a validated spec to walls, obstacles and a Room.

:mod:`symloc.sim.world_file` reads and writes the format into a
:class:`~symloc.sim.world_file.WorldSpec`; this module turns it (or any
:class:`~symloc.sim.world_spec.WorldParts`) into the :class:`~symloc.sim.rooms.Room` it
describes: the outline (with corner cuts), the walls with their door gaps and textures, furniture, pillars
and glass panels (checked to stand inside the room and apart), the lab around a room of boards,
and the people's paths (checked to stay clear). Every problem is a
:class:`~symloc.errors.WorldError` naming the file and the key path.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from symloc.sim.rooms import WALL_HEIGHT, Room, lab
from symloc.sim.world import (
    MATERIAL_BOARD,
    MATERIAL_DARK,
    MATERIAL_FURNITURE,
    MATERIAL_GLASS,
    MATERIAL_PHOTO,
    MATERIAL_WALL,
    World,
    points_in_polygon,
    segments_cross,
)
from symloc.sim.world_spec import (
    LAB_WALL_HEIGHT,
    MATERIALS,
    TEXTURE_POOL,
    ErrorContext,
    RoomSpec,
    WorldParts,
)

__all__ = ["DOOR_HEIGHT", "assemble", "bare_outline", "corner_points"]

FloatArray = NDArray[np.float64]

DOOR_HEIGHT = 2.0
"""Height [m] of a closed door's leaf (lower if the walls are lower)."""

_MIN_GAP = 0.01  # furniture keeps at least this [m] from walls and from each other
_CIRCLE_SAGITTA = 0.002  # facets of a round wall deviate at most this [m] from the circle
_BOUNDARY_VERTICES = 256  # outline of a round room for inside tests


@dataclass(frozen=True)
class _Outline:
    corners: FloatArray  # (V, 2) polygon corners as listed (empty for a circle)
    boundary: FloatArray  # (B, 2) counter-clockwise interior outline after corner cuts
    straight: list[tuple[FloatArray, FloatArray]]  # wall i after the cuts (V entries)
    cuts: list[tuple[int, FloatArray, FloatArray]]  # corner i's cut facet
    circle: tuple[float, float, float] | None


def _rot(points: FloatArray, yaw_deg: float) -> FloatArray:
    th = math.radians(yaw_deg)
    rot = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    return np.asarray(points @ rot.T, dtype=np.float64)


def corner_points(room: RoomSpec) -> FloatArray:
    """The corners ``(V, 2)`` [m] of a polygonal room as its walls are numbered (not a circle)."""
    c = np.array(room.center, dtype=np.float64)
    if room.shape == "polygon":
        return np.array(room.polygon, dtype=np.float64)
    if room.shape == "regular":
        n = room.n
        ang = -math.pi / 2 - math.pi / n + 2 * math.pi * np.arange(n) / n
        local = room.gv * np.column_stack([np.cos(ang), np.sin(ang)])
    else:
        w, d = (room.width, room.depth) if room.shape == "rectangle" else (room.length, room.width)
        local = np.array([[-w / 2, -d / 2], [w / 2, -d / 2], [w / 2, d / 2], [-w / 2, d / 2]])
    return c + _rot(local, room.yaw_deg)


def _polygon_problem(v: FloatArray) -> tuple[int, str] | None:
    """The first problem of a polygon as (vertex index, message), or None if it is simple."""
    n = v.shape[0]
    nxt = np.roll(v, -1, axis=0)
    edge = nxt - v
    lengths = np.hypot(*edge.T)
    for i in range(n):
        if lengths[i] < 1e-6:
            return (i + 1) % n, f"repeats vertex [{i}] (a zero-length wall)"
    for i in range(n):
        a, b = edge[i - 1], edge[i]
        cross = a[0] * b[1] - a[1] * b[0]
        if abs(cross) <= 1e-9 * lengths[i - 1] * lengths[i] and float(a @ b) < 0:
            return (
                i,
                "folds back on the wall before it (a zero-width spike: clockwise or counter-clockwise is ambiguous)",
            )
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            if segments_cross(v[i], nxt[i], v[j], nxt[j]):
                return i, (
                    f"wall {i} ([{i}] to [{(i + 1) % n}]) crosses wall {j} ([{j}] to"
                    f" [{(j + 1) % n}]); expected a simple polygon, whose orientation is clear"
                )
    area2 = float(np.sum(v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]))
    if abs(area2) <= 1e-9 * float(np.max(lengths)) ** 2:
        return -1, "zero area (collinear vertices): counter-clockwise or clockwise is ambiguous"
    return None


def _ccw(v: FloatArray) -> FloatArray:
    nxt = np.roll(v, -1, axis=0)
    area2 = float(np.sum(v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]))
    return v if area2 > 0 else v[::-1].copy()


def _outline(ctx: ErrorContext, room: RoomSpec) -> _Outline:
    if room.shape == "circle":
        if room.chamfer:
            raise ctx.error("room.chamfer", "a round room has no corners to cut")
        cx, cy = room.center
        r = room.radius
        ang = -math.pi / 2 + 2 * math.pi * np.arange(_BOUNDARY_VERTICES) / _BOUNDARY_VERTICES
        boundary = np.column_stack([cx + r * np.cos(ang), cy + r * np.sin(ang)])
        return _Outline(np.zeros((0, 2)), boundary, [], [], (cx, cy, r))
    v = corner_points(room)
    n = v.shape[0]
    problem = _polygon_problem(v)
    if problem is not None:
        idx, msg = problem
        path = "room.polygon" if room.shape == "polygon" else f"room.{room.shape}"
        where = f"{path}[{idx}]" if idx >= 0 and room.shape == "polygon" else path
        raise ctx.error(where, msg)
    cuts = room.chamfer
    if len(cuts) == 1:
        cuts = cuts * n
    if cuts and len(cuts) != n:
        raise ctx.error(
            "room.chamfer", f"expected one number or {n} (one per corner), got {len(cuts)}"
        )
    c = np.array(cuts if cuts else [0.0] * n)
    nxt = np.roll(v, -1, axis=0)
    lengths = np.hypot(*(nxt - v).T)
    for i in range(n):
        if c[i] + c[(i + 1) % n] > lengths[i] - 0.05:
            raise ctx.error(
                "room.chamfer",
                f"cuts of {c[i]} m and {c[(i + 1) % n]} m at corners {i} and {(i + 1) % n} leave"
                f" less than 0.05 m of wall {i} ({lengths[i]:.3f} m long)",
            )
    unit = (nxt - v) / lengths[:, None]
    straight = [(v[i] + c[i] * unit[i], nxt[i] - c[(i + 1) % n] * unit[i]) for i in range(n)]
    verts: list[FloatArray] = []
    facets: list[tuple[int, FloatArray, FloatArray]] = []
    for i in range(n):
        if c[i] > 0:
            p_in = straight[i - 1][1]
            p_out = straight[i][0]
            verts.extend([p_in, p_out])
            facets.append((i, p_in, p_out))
        else:
            verts.append(v[i])
    cut = np.array(verts)
    if cuts:
        problem = _polygon_problem(cut)
        if problem is not None:
            raise ctx.error(
                "room.chamfer", f"the cut outline is not a simple polygon: {problem[1]}"
            )
    return _Outline(v, _ccw(cut), straight, facets, None)


def _texture_ids(n: int, seed: int | None, first: int) -> list[int]:
    if seed is None:
        return list(range(first, first + n))
    rng = np.random.default_rng([seed, 0x7E57])
    return [int(k) for k in rng.choice(TEXTURE_POOL, size=n, replace=False)]


def _texture_material(t: int | str) -> int:
    if t == "plain":
        return MATERIAL_WALL
    if t == "dark":
        return MATERIAL_DARK
    return MATERIAL_PHOTO + int(t)


@dataclass
class _Walls:
    segs: list[FloatArray] = field(default_factory=list)
    mats: list[int] = field(default_factory=list)
    heights: list[float] = field(default_factory=list)
    tex_u: list[tuple[float, float]] = field(default_factory=list)

    def add(self, a: FloatArray, b: FloatArray, mat: int, h: float, u: tuple[float, float]) -> None:
        if float(np.hypot(*(b - a))) > 1e-9:
            self.segs.append(np.concatenate([a, b]))
            self.mats.append(mat)
            self.heights.append(h)
            self.tex_u.append(u)

    def world(self) -> World:
        if not self.segs:
            return World()
        return World(
            np.array(self.segs),
            np.array(self.heights),
            np.array(self.mats),
            wall_tex_u=np.array(self.tex_u),
        )


def _door_gaps(
    ctx: ErrorContext, spec: WorldParts, outline: _Outline
) -> dict[int, list[tuple[float, float, bool, int]]]:
    """Per wall, the door gaps as (start, end) [m along the wall, or rad for a circle]."""
    gaps: dict[int, list[tuple[float, float, bool, int]]] = {}
    for i, d in enumerate(spec.doors):
        path = f"doors[{i}]"
        if outline.circle is not None:
            r = outline.circle[2]
            if d.wall != 0:
                raise ctx.error(f"{path}.wall", f"a round room has one wall, 0; got {d.wall}")
            if d.width > r:
                raise ctx.error(
                    f"{path}.width",
                    f"{d.width} m is too wide for a round wall of radius {r} m (at most the radius)",
                )
            phi = -math.pi / 2 + 2 * math.pi * d.at
            half = math.asin(d.width / (2 * r))
            gaps.setdefault(0, []).append((phi - half, phi + half, d.open, i))
            continue
        n = outline.corners.shape[0]
        if d.wall >= n:
            raise ctx.error(f"{path}.wall", f"expected a wall index in [0, {n - 1}], got {d.wall}")
        a = outline.corners[d.wall]
        b = outline.corners[(d.wall + 1) % n]
        length = float(np.hypot(*(b - a)))
        sa, sb = outline.straight[d.wall]
        lo_ok = float(np.hypot(*(sa - a)))
        hi_ok = float(np.hypot(*(sb - a)))
        if d.width >= hi_ok - lo_ok - 0.02:
            raise ctx.error(
                f"{path}.width",
                f"a door of {d.width} m is wider than wall {d.wall} ({hi_ok - lo_ok:.3f} m of"
                " straight wall); expected a narrower door",
            )
        s0 = d.at * length - d.width / 2
        s1 = d.at * length + d.width / 2
        if s0 < lo_ok + 0.01 or s1 > hi_ok - 0.01:
            raise ctx.error(
                f"{path}.at",
                f"a door of {d.width} m centred at {d.at} of wall {d.wall} ({length:.3f} m) runs"
                " past the wall's end or corner cut; expected it to fit on the wall",
            )
        gaps.setdefault(d.wall, []).append((s0, s1, d.open, i))
    for wall, items in gaps.items():
        items.sort()
        for (_a0, a1, _, i), (b0, _b1, _, j) in itertools.pairwise(items):
            if b0 < a1 + 0.01:
                raise ctx.error(
                    f"doors[{max(i, j)}]", f"overlaps doors[{min(i, j)}] on wall {wall}"
                )
    return gaps


def _wall_materials(
    ctx: ErrorContext, spec: WorldParts, outline: _Outline, n_tiles: int
) -> tuple[list[int], list[int]]:
    """Materials of the walls (or round-wall tiles) and of the corner-cut facets."""
    n = n_tiles if outline.circle is not None else outline.corners.shape[0]
    n_cuts = len(outline.cuts)
    if spec.room.in_lab:
        return [MATERIAL_BOARD] * n, [MATERIAL_BOARD] * n_cuts
    lab_spec = spec.lab
    if lab_spec.textures:
        if outline.circle is None and len(lab_spec.textures) != n:
            raise ctx.error(
                "lab.textures",
                f"expected {n} entries (one per wall of the room), got {len(lab_spec.textures)}",
            )
        return [_texture_material(t) for t in lab_spec.textures], [MATERIAL_WALL] * n_cuts
    if not lab_spec.textured:
        return [MATERIAL_WALL] * n, [MATERIAL_WALL] * n_cuts
    ids = _texture_ids(n + n_cuts, spec.seed, 0)
    mats = [MATERIAL_PHOTO + k for k in ids]
    return mats[:n], mats[n:]


def _polygon_walls(
    ctx: ErrorContext,
    spec: WorldParts,
    outline: _Outline,
    gaps: dict[int, list[tuple[float, float, bool, int]]],
) -> _Walls:
    h = spec.room.wall_height
    mats, cut_mats = _wall_materials(ctx, spec, outline, 0)
    leaf_h = min(h, DOOR_HEIGHT)
    out = _Walls()
    n = outline.corners.shape[0]
    for i in range(n):
        a = outline.corners[i]
        b = outline.corners[(i + 1) % n]
        length = float(np.hypot(*(b - a)))
        unit = (b - a) / length
        sa, sb = outline.straight[i]
        s = float(np.hypot(*(sa - a)))
        end = float(np.hypot(*(sb - a)))
        for g0, g1, is_open, _ in gaps.get(i, []):
            out.add(a + s * unit, a + g0 * unit, mats[i], h, (s / length, g0 / length))
            if not is_open:
                out.add(a + g0 * unit, a + g1 * unit, MATERIAL_FURNITURE, leaf_h, (0.0, 1.0))
            s = g1
        out.add(a + s * unit, a + end * unit, mats[i], h, (s / length, end / length))
    for (_, p_in, p_out), m in zip(outline.cuts, cut_mats, strict=True):
        out.add(p_in, p_out, m, h, (0.0, 1.0))
    return out


def _circle_walls(
    ctx: ErrorContext,
    spec: WorldParts,
    outline: _Outline,
    gaps: dict[int, list[tuple[float, float, bool, int]]],
) -> World:
    assert outline.circle is not None
    cx, cy, r = outline.circle
    h = spec.room.wall_height
    explicit = bool(spec.lab.textures) and not spec.room.in_lab
    if not gaps and not explicit:
        mats, _ = _wall_materials(ctx, spec, outline, 1)
        return World(circles=np.array([[cx, cy, r]]), circle_heights=h, circle_materials=mats[0])
    n_tiles = len(spec.lab.textures) if explicit else max(1, round(2 * math.pi * r / h))
    mats, _ = _wall_materials(ctx, spec, outline, n_tiles)
    start = -math.pi / 2
    step = 2 * math.acos(max(-1.0, 1.0 - _CIRCLE_SAGITTA / r))
    k = max(64, math.ceil(2 * math.pi / step))
    breaks = [
        start + 2 * math.pi * np.arange(k + 1) / k,
        start + 2 * math.pi * np.arange(n_tiles + 1) / n_tiles,
    ]
    door_list = gaps.get(0, [])
    for g0, g1, _, _ in door_list:
        breaks.append(np.mod(np.array([g0, g1]) - start, 2 * math.pi) + start)
    th = np.unique(np.round(np.concatenate(breaks), 12))
    leaf_h = min(h, DOOR_HEIGHT)
    out = _Walls()
    tile_angle = 2 * math.pi / n_tiles
    for t0, t1 in itertools.pairwise(th):
        mid = 0.5 * (t0 + t1)
        if any(np.mod(mid - g0, 2 * math.pi) < (g1 - g0) for g0, g1, _, _ in door_list):
            continue
        tile = min(int((mid - start) // tile_angle), n_tiles - 1)
        u0 = (t0 - start) / tile_angle - tile
        u1 = (t1 - start) / tile_angle - tile
        a = np.array([cx + r * math.cos(t0), cy + r * math.sin(t0)])
        b = np.array([cx + r * math.cos(t1), cy + r * math.sin(t1)])
        out.add(a, b, mats[tile], h, (u0, u1))
    for g0, g1, is_open, _ in door_list:
        if not is_open:
            a = np.array([cx + r * math.cos(g0), cy + r * math.sin(g0)])
            b = np.array([cx + r * math.cos(g1), cy + r * math.sin(g1)])
            out.add(a, b, MATERIAL_FURNITURE, leaf_h, (0.0, 1.0))
    return out.world()


@dataclass(frozen=True)
class _Solid:
    path: str
    polygon: FloatArray | None  # filled polygon (box)
    circle: tuple[float, float, float] | None  # filled circle
    segment: FloatArray | None  # a thin panel (4,)

    def outline_points(self) -> FloatArray:
        if self.polygon is not None:
            return self.polygon
        if self.circle is not None:
            cx, cy, r = self.circle
            ang = 2 * math.pi * np.arange(32) / 32
            return np.column_stack([cx + r * np.cos(ang), cy + r * np.sin(ang)])
        assert self.segment is not None
        return self.segment.reshape(2, 2)

    def world(self) -> World:
        if self.circle is not None:
            return World(circles=np.array([self.circle]))
        if self.polygon is not None:
            p = self.polygon
            return World(np.column_stack([p, np.roll(p, -1, axis=0)]))
        assert self.segment is not None
        return World(self.segment[None])

    def contains(self, pts: FloatArray) -> NDArray[np.bool_]:
        if self.polygon is not None:
            return points_in_polygon(pts, self.polygon)
        if self.circle is not None:
            cx, cy, r = self.circle
            return np.asarray(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) < r)
        return np.zeros(pts.shape[0], dtype=bool)


def _gap(a: _Solid, b: _Solid) -> float:
    """Clearance [m] between two solids (<= 0 when they overlap)."""
    if np.any(a.contains(b.outline_points())) or np.any(b.contains(a.outline_points())):
        return -1.0
    if a.circle is not None and b.circle is not None:
        return float(
            math.hypot(a.circle[0] - b.circle[0], a.circle[1] - b.circle[1])
            - a.circle[2]
            - b.circle[2]
        )
    if a.circle is not None:
        a, b = b, a
    wa = a.world()
    if b.circle is not None:
        return float(wa.distance(np.array(b.circle[:2])[None])[0] - b.circle[2])
    wb = b.world()
    for sa in wa.walls:
        for sb in wb.walls:
            if segments_cross(sa[:2], sa[2:], sb[:2], sb[2:]):
                return 0.0
    return float(min(wa.distance(b.outline_points()).min(), wb.distance(a.outline_points()).min()))


def _solids(spec: WorldParts) -> list[_Solid]:
    out: list[_Solid] = []
    for group, items in (("furniture", spec.furniture), ("pillars", spec.pillars)):
        for i, f in enumerate(items):
            path = f"{group}[{i}]" + (f".{f.kind}" if group == "furniture" else "")
            if f.kind == "box":
                out.append(_Solid(path, f.footprint(), None, None))
            else:
                out.append(_Solid(path, None, (f.center[0], f.center[1], f.radius), None))
    for i, g in enumerate(spec.glass):
        out.append(_Solid(f"glass[{i}]", None, None, np.array([*g.start, *g.end])))
    return out


def _check_solids(
    ctx: ErrorContext, solids: list[_Solid], outline: _Outline, room_walls: World
) -> None:
    corners = _wall_points(room_walls)
    for s in solids:
        pts = s.outline_points()
        inside = bool(np.all(points_in_polygon(pts, outline.boundary)))
        if s.circle is not None:
            gap = float(room_walls.distance(np.array(s.circle[:2])[None])[0] - s.circle[2])
        else:
            gap = float(room_walls.distance(pts).min())
            if corners.shape[0]:
                gap = min(gap, float(s.world().distance(corners).min()))
            for w in room_walls.walls:
                if any(segments_cross(a, b, w[:2], w[2:]) for a, b in _edges(s)):
                    gap = 0.0
        if not inside or gap < _MIN_GAP:
            raise ctx.error(
                s.path,
                f"lies outside the room or within {_MIN_GAP} m of its walls (clearance"
                f" {max(gap, 0.0):.3f} m); expected it inside the room",
            )
    for i, a in enumerate(solids):
        for b in solids[:i]:
            if _gap(a, b) < _MIN_GAP:
                raise ctx.error(a.path, f"overlaps {b.path} (or is within {_MIN_GAP} m of it)")


def _wall_points(w: World) -> FloatArray:
    pts = [w.walls[:, :2], w.walls[:, 2:]]
    return np.concatenate(pts) if w.n_walls else np.zeros((0, 2))


def _edges(s: _Solid) -> list[tuple[FloatArray, FloatArray]]:
    if s.polygon is not None:
        p = s.polygon
        return [(p[i], p[(i + 1) % len(p)]) for i in range(len(p))]
    if s.segment is not None:
        return [(s.segment[:2], s.segment[2:])]
    return []


def _solid_world(spec: WorldParts) -> World:
    parts: list[World] = []
    for f in (*spec.furniture, *spec.pillars):
        mat = MATERIALS[f.material]
        if f.kind == "box":
            p = f.footprint()
            parts.append(World(np.column_stack([p, np.roll(p, -1, axis=0)]), f.height, mat))
        else:
            parts.append(
                World(
                    circles=np.array([[*f.center, f.radius]]),
                    circle_heights=f.height,
                    circle_materials=mat,
                )
            )
    for g in spec.glass:
        parts.append(World(np.array([[*g.start, *g.end]]), g.height, MATERIAL_GLASS))
    return World.merge(parts)


def _area_centroid(v: FloatArray) -> FloatArray:
    nxt = np.roll(v, -1, axis=0)
    cross = v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]
    a = cross.sum() / 2.0
    return np.array(
        [
            np.sum((v[:, 0] + nxt[:, 0]) * cross) / (6 * a),
            np.sum((v[:, 1] + nxt[:, 1]) * cross) / (6 * a),
        ]
    )


def _lab_world(
    ctx: ErrorContext, spec: WorldParts, boundary: FloatArray, center: FloatArray
) -> World:
    ls = spec.lab
    w0, d0 = ls.size if ls.size is not None else (8.0, 10.0)
    xmin, ymin = boundary.min(axis=0)
    xmax, ymax = boundary.max(axis=0)
    # centred on the room: it must clear the room by the margin on both sides
    half_w = max(w0 / 2, center[0] - xmin + ls.margin, xmax - center[0] + ls.margin)
    half_d = max(d0 / 2, center[1] - ymin + ls.margin, ymax - center[1] + ls.margin)
    n_seg = len(ls.textures) if ls.textures else 12
    if n_seg < 4:
        raise ctx.error(
            "lab.textures", f"a lab has at least 4 walls; expected >= 4 entries, got {n_seg}"
        )
    geo = lab(
        2 * half_w, 2 * half_d, center=center, n_segments=n_seg, height=WALL_HEIGHT, textured=False
    )
    if ls.textures:
        mats = [_texture_material(t) for t in ls.textures]
    elif ls.textured:
        mats = [MATERIAL_PHOTO + k for k in _texture_ids(n_seg, spec.seed, 1)]
    else:
        mats = [MATERIAL_WALL] * n_seg
    return World(geo.walls, WALL_HEIGHT, np.array(mats))


def _check_lab_keys(ctx: ErrorContext, spec: WorldParts) -> None:
    if not spec.room.in_lab and (spec.lab.size is not None or spec.lab.margin != 1.5):
        raise ctx.error(
            "lab.size" if spec.lab.size is not None else "lab.margin",
            f"only used for a room of boards (room.wall_height < {LAB_WALL_HEIGHT} m) inside a lab",
        )


_KIND = {
    "regular": "polygon",
    "polygon": "polygon",
    "circle": "circle",
    "rectangle": "rectangle",
    "corridor": "corridor",
}


def assemble(spec: WorldParts) -> Room:
    """Validate ``spec`` and assemble its Room (orders not yet computed: 1, symmetry None)."""
    ctx = ErrorContext(spec.source)
    _check_lab_keys(ctx, spec)
    outline = _outline(ctx, spec.room)
    gaps = _door_gaps(ctx, spec, outline)
    if outline.circle is None:
        room_world = _polygon_walls(ctx, spec, outline, gaps).world()
    else:
        room_world = _circle_walls(ctx, spec, outline, gaps)
    if spec.room.in_lab and spec.lab.textures and len(spec.lab.textures) < 4:
        raise ctx.error(
            "lab.textures",
            f"a lab has at least 4 walls; expected >= 4 entries, got {len(spec.lab.textures)}",
        )
    solids = _solids(spec)
    bare = _bare_walls(outline)
    _check_solids(ctx, solids, outline, bare)
    boundary = outline.boundary
    center = _area_centroid(boundary) if outline.circle is None else np.array(outline.circle[:2])
    parts = [room_world, _solid_world(spec)]
    if spec.room.in_lab:
        parts.append(_lab_world(ctx, spec, boundary, center))
    world = World.merge(parts)
    for i, p in enumerate(spec.people):
        for j in range(1, len(p.path) + (1 if p.loop else 0)):
            if math.dist(p.path[j - 1], p.path[j % len(p.path)]) < 1e-6:
                raise ctx.error(
                    f"people[{i}].path[{j % len(p.path)}]", "repeats the point before it"
                )
    people = tuple(p.person() for p in spec.people)
    obstacles = tuple(f.footprint() for f in (*spec.furniture, *spec.pillars) if f.kind == "box")
    circles = [
        [*f.center, f.radius] for f in (*spec.furniture, *spec.pillars) if f.kind == "cylinder"
    ]
    regular = spec.room.shape in ("regular", "circle") and not spec.room.chamfer
    if spec.room.shape == "rectangle":
        regular = math.isclose(spec.room.width, spec.room.depth) and not spec.room.chamfer
    room = Room(
        name=spec.name,
        kind=_KIND[spec.room.shape],
        world=world,
        boundary=boundary,
        corners=boundary.copy() if outline.circle is None else np.zeros((0, 2)),
        center=center,
        gv_distance=float(np.max(np.hypot(*(boundary - center).T))),
        shape_order=1,
        order=1,
        regular=regular,
        door=any(d.open for d in spec.doors),
        n_furniture=len(spec.furniture),
        wall_height=spec.room.wall_height,
        room_world=room_world,
        people=people,
        obstacles=obstacles,
        obstacle_circles=np.array(circles, dtype=np.float64).reshape(-1, 3),
    )
    _check_people(ctx, spec, room)
    return room


def _bare_walls(outline: _Outline) -> World:
    if outline.circle is not None:
        return World(circles=np.array([outline.circle]))
    b = outline.boundary
    return World(np.column_stack([b, np.roll(b, -1, axis=0)]))


def _check_people(ctx: ErrorContext, spec: WorldParts, room: Room) -> None:
    for i, p in enumerate(spec.people):
        pts = np.array(p.path, dtype=np.float64)
        closed = np.vstack([pts, pts[:1]]) if p.loop else pts
        for j in range(closed.shape[0] - 1):
            a, b = closed[j], closed[j + 1]
            length = float(np.hypot(*(b - a)))
            if length < 1e-6:
                raise ctx.error(
                    f"people[{i}].path[{(j + 1) % len(pts)}]", "repeats the point before it"
                )
            t = np.linspace(0.0, 1.0, max(2, math.ceil(length / 0.05) + 1))
            ok = room.is_free(a + t[:, None] * (b - a), p.radius)
            if not np.all(ok):
                raise ctx.error(
                    f"people[{i}].path[{j}]",
                    f"the leg to point [{(j + 1) % len(pts)}] leaves the room or passes within"
                    f" {p.radius} m (the person's radius) of a wall or obstacle",
                )


def bare_outline(spec: WorldParts) -> World:
    """The room's outline alone (after corner cuts, no doors): what ``shape_order`` is of."""
    return _bare_walls(_outline(ErrorContext(spec.source), spec.room))
