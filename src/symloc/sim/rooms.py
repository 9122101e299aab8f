"""Room builders and the ``Room`` ground-truth record.

Every builder returns a :class:`Room`: the :class:`~symloc.sim.world.World` to simulate plus the
ground truth a test or experiment needs (kind, rotational symmetry order k, geometric centre,
G-V distance = centre to vertex as in the paper's Table 1, corners, interior sampling).

The paper's real room is a 3 m x 3 m square of low plastic boards inside a larger lab whose
walls carry posters, windows and shelves; the lidar is mounted below the top of the boards, so
it sees only the boards, while the camera sees the boards in the lower part of its image and the
lab above them. ``build_room(..., lab=True)`` reproduces that: room walls become 0.4 m boards
and a 12-segment lab (2.5 m walls, one real photograph per segment) surrounds the room.
With ``lab=False`` the room walls themselves are 2.5 m tall (the paper's Gazebo rooms).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import as_rng, check_positive
from symloc.errors import ConfigurationError, WorldError
from symloc.sim.free_space import FreeSpace, free_space_grid
from symloc.sim.people import Person, people_world
from symloc.sim.symmetry_truth import SymmetryTruth, lidar_symmetry
from symloc.sim.world import (
    MATERIAL_BOARD,
    MATERIAL_FURNITURE,
    MATERIAL_PHOTO,
    MATERIAL_WALL,
    World,
    check_polygon,
    points_in_polygon,
    polygon_walls,
)

__all__ = [
    "BOARD_HEIGHT",
    "ROBOT_RADIUS",
    "ROOM_NAMES",
    "WALL_HEIGHT",
    "Room",
    "add_furniture",
    "build_room",
    "circular_room",
    "hallway",
    "l_shaped_room",
    "lab",
    "points_in_polygon",
    "rectangle_room",
    "regular_polygon_room",
    "with_lab",
    "with_truth",
]

FloatArray = NDArray[np.float64]

BOARD_HEIGHT = 0.4
"""Height [m] of the low boards that enclose the paper's real room."""
WALL_HEIGHT = 2.5
"""Height [m] of full-height walls (lab walls, Gazebo-style rooms)."""
FURNITURE_HEIGHT = 0.75
DOOR_WIDTH = 0.8
ROBOT_RADIUS = 0.18
"""Default robot radius [m] for free-space queries (a TurtleBot3 Burger is 0.105 m, a Waffle
0.177 m; the paper's robot about 0.18 m)."""

_POLYGON_SIDES = {"triangle": 3, "square": 4, "pentagon": 5, "hexagon": 6, "octagon": 8}
ROOM_NAMES = (*_POLYGON_SIDES, "circle", "rectangle", "hallway", "l_shaped")
"""Names accepted by :func:`build_room`."""

RECTANGLE_ASPECT = 1.5
HALLWAY_ASPECT = 6.0
_CIRCLE_DOOR_SEGMENTS = 96


@dataclass(frozen=True, eq=False)
class Room:
    """A simulated room and its ground truth.

    Attributes
    ----------
    name : str
        Builder name (``"square"``, ``"circle"``, ...).
    kind : str
        ``"polygon"`` (regular n-gon), ``"circle"``, ``"rectangle"``, ``"hallway"`` or
        ``"l_shaped"``.
    world : World
        Everything to simulate: the room walls, furniture, and the lab if any.
    boundary : ndarray of shape (V, 2)
        The room's interior outline [m], counter-clockwise (a 128-gon for a circle).
    corners : ndarray of shape (K, 2)
        The room's true corners [m] (empty for a circle).
    center : ndarray of shape (2,)
        Geometric centre [m] (the centroid of the outline).
    gv_distance : float
        Centre to vertex [m] (the paper's G-V distance); the radius for a circle; the largest
        centre-to-corner distance for an L-shaped room.
    shape_order : int
        Rotational symmetry order of the bare outline, computed from it: n for a regular n-gon,
        2 for a rectangle or hallway, 1 for an L-shape, 0 for a circle (continuous symmetry).
    order : int
        Rotational symmetry order of what the lidar sees, computed from the world by
        :func:`symloc.sim.symmetry_truth.lidar_symmetry` (see :attr:`symmetry`): ``shape_order``
        for a closed, empty room, 1 when a door gap or furniture breaks the symmetry.
    regular : bool
        True for a regular polygon or a circle.
    door : bool
        Whether the room has a door gap.
    n_furniture : int
        Number of furniture items (boxes + round tables) inside.
    wall_height : float
        Height [m] of the room's own walls (0.4 m boards inside a lab, else 2.5 m).
    room_world : World
        The room's own walls (and closed doors), without furniture or lab.
    people : tuple of Person
        People walking in the room (see :meth:`world_at`); not part of :attr:`world`.
    obstacles : tuple of ndarray of shape (V, 2)
        Footprints [m] of solid obstacles inside the room (boxes, square pillars), whatever
        their height: the robot cannot stand inside them.
    obstacle_circles : ndarray of shape (C, 3)
        Round solid obstacles ``cx, cy, r`` [m] (round tables, cylinders, round pillars).
    symmetry : SymmetryTruth or None
        The computed ground truth (:func:`symloc.sim.symmetry_truth.lidar_symmetry`) that
        ``order`` comes from; None for a room assembled by hand.
    """

    name: str
    kind: str
    world: World
    boundary: FloatArray
    corners: FloatArray
    center: FloatArray
    gv_distance: float
    shape_order: int
    order: int
    regular: bool
    door: bool = False
    n_furniture: int = 0
    wall_height: float = WALL_HEIGHT
    room_world: World = field(default_factory=World)
    people: tuple[Person, ...] = ()
    obstacles: tuple[FloatArray, ...] = ()
    obstacle_circles: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    symmetry: SymmetryTruth | None = None
    _cache: dict[tuple[float, float], FreeSpace] = field(
        init=False, default_factory=dict, repr=False
    )
    _truths: dict[bool, SymmetryTruth] = field(init=False, default_factory=dict, repr=False)

    def truth(self, *, glass_visible: bool = False) -> SymmetryTruth:
        """The true symmetry of what the lidar sees, glass transparent (the default, as
        :attr:`symmetry` and :attr:`order`) or opaque (a lidar model that sees glass like a
        wall, e.g. the ``ideal`` sensor regime). Computed once per choice."""
        if not glass_visible and self.symmetry is not None:
            return self.symmetry
        if glass_visible not in self._truths:
            self._truths[glass_visible] = lidar_symmetry(
                self.world, self.boundary, glass_visible=glass_visible
            )
        return self._truths[glass_visible]

    def world_at(self, t: float, robot: ArrayLike | None = None) -> World:
        """The static world plus the people where they are at time ``t`` [s]; with the
        ``robot``'s position (2,) or pose (3,) [m], those whose path crosses it (radius
        :data:`ROBOT_RADIUS`) stepped aside (:func:`~symloc.sim.people.people_world`)."""
        if not self.people:
            return self.world
        clear = None if robot is None else (robot, ROBOT_RADIUS)
        return self.world + people_world(self.people, float(t), clear)

    def is_free(self, points: ArrayLike, clearance: float = ROBOT_RADIUS) -> NDArray[np.bool_]:
        """``(N,)`` True where a round robot of radius ``clearance`` [m] fits at points ``(N, 2)``.

        Free means: inside the room outline and at least ``clearance`` from it (the whole robot
        is in the room, not half-way through a door), at least ``clearance`` from every static
        wall, circle and furniture outline of any height (a robot collides with a low box the
        lidar does not see), and not inside a solid obstacle. People are not counted (they
        move).
        """
        c = check_positive(clearance, "clearance", allow_zero=True)
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        out = self.contains(p)
        b = self.boundary
        outline = World(np.column_stack([b, np.roll(b, -1, axis=0)]))
        step = 20_000
        for i in range(0, p.shape[0], step):
            sl = slice(i, i + step)
            idx = np.flatnonzero(out[sl]) + i
            if idx.size:
                q = p[idx]
                out[idx] = (self.world.distance(q) >= c) & (outline.distance(q) >= c)
        for poly in self.obstacles:
            out &= ~points_in_polygon(p, poly)
        oc = self.obstacle_circles
        if oc.shape[0] and p.shape[0]:
            d = np.hypot(p[:, None, 0] - oc[:, 0], p[:, None, 1] - oc[:, 1]) - oc[:, 2]
            out &= np.all(d >= c, axis=1)
        return out

    def free_space(
        self, clearance: float = ROBOT_RADIUS, resolution: float | None = None
    ) -> FreeSpace:
        """The free-space grid for a robot of radius ``clearance`` [m] (computed once, cached).

        ``resolution`` [m] defaults to 5 cm, coarser for very large rooms (at most about 400 000
        cells).
        """
        c = check_positive(clearance, "clearance", allow_zero=True)
        xmin, ymin = self.boundary.min(axis=0)
        xmax, ymax = self.boundary.max(axis=0)
        if resolution is None:
            res = max(0.05, math.sqrt((xmax - xmin) * (ymax - ymin) / 400_000.0))
        else:
            res = check_positive(resolution, "resolution")
        key = (c, res)
        if key not in self._cache:
            self._cache[key] = free_space_grid(
                self.boundary,
                self.world,
                solids=self.obstacles,
                solid_circles=self.obstacle_circles,
                resolution=res,
                clearance=c,
                center=self.center,
            )
        return self._cache[key]

    def is_reachable(self, points: ArrayLike, clearance: float = ROBOT_RADIUS) -> NDArray[np.bool_]:
        """``(N,)`` True where a robot fits and can drive to the room centre (or, if it cannot
        stand at the centre, within the largest free region)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        ok = self.is_free(p, clearance)
        if np.any(ok):
            ok[ok] = self.free_space(clearance).in_reachable(p[ok])
        return ok

    def sample_pose(
        self,
        rng: np.random.Generator | int | None = None,
        clearance: float = ROBOT_RADIUS,
        *,
        reachable: bool = True,
    ) -> FloatArray:
        """A uniformly random pose ``(3,)`` (x [m], y [m], theta [rad]) where the robot fits.

        Positions are uniform over the free space (rejection sampling from the outline's
        bounding box, so right up to ``clearance`` from the walls and furniture, not on a grid);
        ``reachable`` keeps only those from which the robot can drive to the room centre (see
        :meth:`is_reachable`); the heading is uniform in (-pi, pi].
        """
        gen = as_rng(rng)
        xmin, ymin = self.boundary.min(axis=0)
        xmax, ymax = self.boundary.max(axis=0)
        for _ in range(200):
            cand = np.column_stack([gen.uniform(xmin, xmax, 256), gen.uniform(ymin, ymax, 256)])
            ok = self.is_reachable(cand, clearance) if reachable else self.is_free(cand, clearance)
            if np.any(ok):
                x, y = cand[int(np.flatnonzero(ok)[0])]
                theta = math.pi - gen.uniform(0.0, 2.0 * math.pi)
                return np.array([x, y, theta])
        raise WorldError(
            f"sample_pose: no place in room {self.name!r} where a robot of radius"
            f" {clearance} m fits"
        )

    @property
    def symmetric(self) -> bool:
        """True if the lidar-visible geometry has a rotational symmetry (order 0 or >= 2)."""
        return self.order != 1

    @property
    def area(self) -> float:
        """Interior area [m^2] of the outline."""
        v = self.boundary
        nxt = np.roll(v, -1, axis=0)
        return float(0.5 * abs(np.sum(v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1])))

    def contains(self, points: ArrayLike) -> NDArray[np.bool_]:
        """``(N,)`` True where points ``(N, 2)`` [m] lie inside the room outline."""
        return points_in_polygon(points, self.boundary)

    def positions_inside(self, n: int, margin: float = 0.3) -> FloatArray:
        """``n`` positions ``(n, 2)`` [m] spread evenly inside the room.

        A square grid, as fine as needed to hold at least ``n`` admissible points, is clipped to
        the room and to a clearance of ``margin`` [m] from every wall, circle and furniture item;
        ``n`` of its points are then taken evenly along the grid order. Deterministic.
        """
        if int(n) != n or n < 1:
            raise ConfigurationError(f"positions_inside: n must be an integer >= 1, got {n}")
        n = int(n)
        margin = check_positive(margin, "margin", allow_zero=True)
        xmin, ymin = self.boundary.min(axis=0)
        xmax, ymax = self.boundary.max(axis=0)
        spacing = math.sqrt(self.area / n)
        for _ in range(200):
            xs = np.arange(xmin + spacing / 2, xmax, spacing)
            ys = np.arange(ymin + spacing / 2, ymax, spacing)
            gx, gy = np.meshgrid(xs, ys)
            cand = np.column_stack([gx.ravel(), gy.ravel()])
            keep = self.contains(cand)
            cand = cand[keep]
            if cand.size:
                cand = cand[self.world.distance(cand) >= margin]
            if cand.shape[0] >= n:
                idx = np.round(np.linspace(0, cand.shape[0] - 1, n)).astype(int)
                return np.asarray(cand[idx], dtype=np.float64)
            spacing *= 0.85
            if spacing < 1e-3:
                break
        raise WorldError(
            f"positions_inside: cannot place {n} positions with margin {margin} m in room"
            f" {self.name!r}; the room is too small for that margin"
        )


def _material_per_wall(n: int, textured: bool, first_photo: int = 0) -> NDArray[np.int64]:
    if not textured:
        return np.full(n, MATERIAL_WALL, dtype=np.int64)
    return MATERIAL_PHOTO + first_photo + np.arange(n, dtype=np.int64)


def _door_arg(door: bool | float, edge_length: float) -> tuple[int, float, float] | None:
    if door is False or door is None:
        return None
    width = DOOR_WIDTH if door is True else float(door)
    if width >= 0.8 * edge_length:
        width = 0.4 * edge_length
    return (0, width, 0.5)


def _room_from_polygon(
    name: str,
    kind: str,
    vertices: FloatArray,
    *,
    regular: bool,
    gv_distance: float | None,
    door: bool | float,
    height: float,
    textured: bool,
) -> Room:
    v = check_polygon(vertices, name)
    edge0 = float(np.hypot(*(v[1] - v[0])))
    door_arg = _door_arg(door, edge0)
    walls = polygon_walls(v, door=door_arg, name=name)
    world = World(walls, height, _material_per_wall(len(walls), textured))
    center = _centroid(v)
    gv = float(np.max(np.hypot(*(v - center).T))) if gv_distance is None else gv_distance
    bare = World(polygon_walls(v, name=name), height)
    return with_truth(
        Room(
            name=name,
            kind=kind,
            world=world,
            boundary=v,
            corners=v.copy(),
            center=center,
            gv_distance=gv,
            shape_order=lidar_symmetry(bare, v).order,
            order=1,
            regular=regular,
            door=door_arg is not None,
            wall_height=height,
            room_world=world,
        )
    )


def with_truth(room: Room) -> Room:
    """``room`` with ``order`` and ``symmetry`` computed from its world (never declared)."""
    truth = lidar_symmetry(room.world, room.boundary)
    return _replace(room, order=truth.order, symmetry=truth)


def _centroid(v: FloatArray) -> FloatArray:
    nxt = np.roll(v, -1, axis=0)
    cross = v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]
    a = cross.sum() / 2.0
    cx = np.sum((v[:, 0] + nxt[:, 0]) * cross) / (6.0 * a)
    cy = np.sum((v[:, 1] + nxt[:, 1]) * cross) / (6.0 * a)
    return np.array([cx, cy])


def regular_polygon_room(
    n: int,
    gv_distance: float,
    *,
    center: ArrayLike = (0.0, 0.0),
    door: bool | float = False,
    height: float = WALL_HEIGHT,
    textured: bool = True,
) -> Room:
    """A regular ``n``-gon room with centre-to-vertex distance ``gv_distance`` [m].

    The bottom edge is horizontal (a square is axis-aligned). ``door`` True leaves a 0.8 m gap
    (a float gives the width) in the middle of edge 0, the bottom edge.
    """
    if int(n) != n or n < 3:
        raise WorldError(f"regular_polygon_room: n must be an integer >= 3, got {n}")
    n = int(n)
    r = check_positive(gv_distance, "gv_distance")
    c = np.asarray(center, dtype=np.float64)
    ang = -math.pi / 2 - math.pi / n + 2 * math.pi * np.arange(n) / n
    v = c + r * np.column_stack([np.cos(ang), np.sin(ang)])
    names = {3: "triangle", 4: "square", 5: "pentagon", 6: "hexagon", 8: "octagon"}
    return _room_from_polygon(
        names.get(n, f"{n}-gon"),
        "polygon",
        v,
        regular=True,
        gv_distance=r,
        door=door,
        height=height,
        textured=textured,
    )


def rectangle_room(
    width: float,
    depth: float,
    *,
    center: ArrayLike = (0.0, 0.0),
    door: bool | float = False,
    height: float = WALL_HEIGHT,
    textured: bool = True,
    kind: str = "rectangle",
) -> Room:
    """An axis-aligned ``width`` x ``depth`` [m] rectangle (order 2; order 4 if square)."""
    w = check_positive(width, "width")
    d = check_positive(depth, "depth")
    c = np.asarray(center, dtype=np.float64)
    v = c + np.array([[-w / 2, -d / 2], [w / 2, -d / 2], [w / 2, d / 2], [-w / 2, d / 2]])
    square = math.isclose(w, d)
    return _room_from_polygon(
        kind,
        kind,
        v,
        regular=square,
        gv_distance=None,
        door=door,
        height=height,
        textured=textured,
    )


def hallway(
    length: float = 12.0,
    width: float = 2.0,
    *,
    center: ArrayLike = (0.0, 0.0),
    door: bool | float = False,
    height: float = WALL_HEIGHT,
    textured: bool = True,
) -> Room:
    """A long closed corridor ``length`` x ``width`` [m] along x (a rectangle, order 2)."""
    return rectangle_room(
        length, width, center=center, door=door, height=height, textured=textured, kind="hallway"
    )


def l_shaped_room(
    size: float,
    *,
    arm: float = 0.5,
    center: ArrayLike = (0.0, 0.0),
    door: bool | float = False,
    height: float = WALL_HEIGHT,
    textured: bool = True,
) -> Room:
    """An L-shaped room: a ``size`` x ``size`` [m] square minus its upper-right quarter-corner.

    ``arm`` (0..1) is the width of each leg as a fraction of ``size``. Order 1 (no rotation
    maps it onto itself). The outline is centred so that its centroid lies at ``center``.
    """
    s = check_positive(size, "size")
    if not 0.0 < arm < 1.0:
        raise WorldError(f"l_shaped_room: arm must be in (0, 1), got {arm}")
    a = arm * s
    v = np.array([[0, 0], [s, 0], [s, a], [a, a], [a, s], [0, s]], dtype=np.float64)
    v = v - _centroid(v) + np.asarray(center, dtype=np.float64)
    return _room_from_polygon(
        "l_shaped",
        "l_shaped",
        v,
        regular=False,
        gv_distance=None,
        door=door,
        height=height,
        textured=textured,
    )


def circular_room(
    radius: float,
    *,
    center: ArrayLike = (0.0, 0.0),
    door: bool | float = False,
    height: float = WALL_HEIGHT,
    textured: bool = True,
) -> Room:
    """A round room of ``radius`` [m] (one circle primitive; continuous symmetry, order 0).

    With a door the wall becomes a 96-segment polygon with a gap (a circle primitive cannot
    have one), and the order drops to 1.
    """
    r = check_positive(radius, "radius")
    c = np.asarray(center, dtype=np.float64)
    ang = 2 * math.pi * np.arange(128) / 128
    boundary = c + r * np.column_stack([np.cos(ang), np.sin(ang)])
    mat = MATERIAL_PHOTO if textured else MATERIAL_WALL
    if door is False or door is None:
        world = World(
            circles=np.array([[c[0], c[1], r]]), circle_heights=height, circle_materials=mat
        )
        has_door = False
    else:
        k = _CIRCLE_DOOR_SEGMENTS
        a2 = -math.pi / 2 + 2 * math.pi * (np.arange(k) + 0.5) / k
        v = c + r * np.column_stack([np.cos(a2), np.sin(a2)])
        walls = polygon_walls(v, name="circle")
        width = DOOR_WIDTH if door is True else float(door)
        mids = 0.5 * (walls[:, :2] + walls[:, 2:])
        bottom = c + np.array([0.0, -r])
        keep = np.hypot(*(mids - bottom).T) > width / 2
        # photo tiles of about the wall height around the circle, as on the round wall
        n_tiles = max(1, round(2 * math.pi * r / height))
        per_tile = k / n_tiles
        j = np.arange(k)
        tile = np.floor(j / per_tile).astype(np.int64)
        u0 = j / per_tile - tile
        u1 = (j + 1) / per_tile - tile
        mats = mat + tile if textured else np.full(k, mat)
        world = World(walls[keep], height, mats[keep], wall_tex_u=np.column_stack([u0, u1])[keep])
        has_door = True
    return with_truth(
        Room(
            name="circle",
            kind="circle",
            world=world,
            boundary=boundary,
            corners=np.zeros((0, 2)),
            center=c.copy(),
            gv_distance=r,
            shape_order=lidar_symmetry(World(circles=np.array([[c[0], c[1], r]]))).order,
            order=1,
            regular=True,
            door=has_door,
            wall_height=height,
            room_world=world,
        )
    )


def lab(
    width: float = 8.0,
    depth: float = 10.0,
    *,
    center: ArrayLike = (0.0, 0.0),
    n_segments: int = 12,
    height: float = WALL_HEIGHT,
    textured: bool = True,
) -> World:
    """The lab around the room: an axis-aligned ``width`` x ``depth`` [m] rectangle.

    Its walls are split into ``n_segments`` (>= 4) straight segments, each with its own
    photograph (``textured``) or the plain wall material, so that different directions look
    different to the camera, as the paper's lab with its posters, windows and shelves does.
    """
    w = check_positive(width, "width")
    d = check_positive(depth, "depth")
    if int(n_segments) != n_segments or n_segments < 4:
        raise WorldError(f"lab: n_segments must be an integer >= 4, got {n_segments}")
    n_segments = int(n_segments)
    c = np.asarray(center, dtype=np.float64)
    corners = c + np.array([[-w / 2, -d / 2], [w / 2, -d / 2], [w / 2, d / 2], [-w / 2, d / 2]])
    sides = np.array([w, d, w, d])
    per_side = np.ones(4, dtype=int)
    for _ in range(n_segments - 4):  # give the next piece to the side with the longest pieces
        per_side[int(np.argmax(sides / per_side))] += 1
    segs: list[FloatArray] = []
    for i in range(4):
        a, b = corners[i], corners[(i + 1) % 4]
        t = np.linspace(0.0, 1.0, per_side[i] + 1)
        pts = a + t[:, None] * (b - a)
        segs.extend(np.concatenate([pts[j], pts[j + 1]]) for j in range(per_side[i]))
    walls = np.array(segs)
    first = 1  # photo 0 is used by a circular room's own wall
    return World(walls, height, _material_per_wall(len(walls), textured, first))


def with_lab(
    room: Room,
    *,
    board_height: float = BOARD_HEIGHT,
    lab_size: tuple[float, float] = (8.0, 10.0),
    margin: float = 1.5,
    n_segments: int = 12,
    textured: bool = True,
) -> Room:
    """Put ``room`` inside a lab, as in the paper's real experiment.

    The room's walls become plain boards of ``board_height`` [m]; the lab (see :func:`lab`) is
    centred on the room and enlarged when needed so that at least ``margin`` [m] separates it
    from the room.
    """
    bh = check_positive(board_height, "board_height")
    xmin, ymin = room.boundary.min(axis=0)
    xmax, ymax = room.boundary.max(axis=0)
    lw = max(lab_size[0], xmax - xmin + 2 * margin)
    ld = max(lab_size[1], ymax - ymin + 2 * margin)
    rw = room.room_world
    boards = World(
        rw.walls,
        np.full(rw.n_walls, bh),
        np.full(rw.n_walls, MATERIAL_BOARD),
        rw.circles,
        np.full(rw.n_circles, bh),
        np.full(rw.n_circles, MATERIAL_BOARD),
        rw.wall_tex_u,
    )
    furniture = _furniture_only(room)
    lab_world = lab(
        lw, ld, center=room.center, n_segments=n_segments, height=WALL_HEIGHT, textured=textured
    )
    return with_truth(
        _replace(
            room,
            world=World.merge([boards, furniture, lab_world]),
            room_world=boards,
            wall_height=bh,
        )
    )


def _furniture_only(room: Room) -> World:
    w = room.world
    wk = np.asarray(w.wall_materials) == MATERIAL_FURNITURE
    ck = np.asarray(w.circle_materials) == MATERIAL_FURNITURE
    return World(
        w.walls[wk],
        np.asarray(w.wall_heights)[wk],
        np.asarray(w.wall_materials)[wk],
        w.circles[ck],
        np.asarray(w.circle_heights)[ck],
        np.asarray(w.circle_materials)[ck],
        np.asarray(w.wall_tex_u)[wk],
    )


def _replace(room: Room, **changes: object) -> Room:
    from dataclasses import replace

    return replace(room, **changes)  # type: ignore[arg-type]


def add_furniture(
    room: Room,
    *,
    boxes: int = 0,
    tables: int = 0,
    rng: np.random.Generator | int | None = None,
    keep_center_free: float = 0.6,
) -> Room:
    """Place ``boxes`` rectangular boxes and ``tables`` round tables asymmetrically inside.

    Sizes, orientations and positions are drawn from ``rng`` (None means the fixed seed 0, so
    the same call builds the same room). Items keep 0.05 m from the walls and 0.25 m from each other and
    stay at least ``keep_center_free`` [m] away from the centre, where the robot goes to look
    around. The order is recomputed from the geometry (furniture taller than the lidar plane
    placed like this breaks any symmetry, so it becomes 1).
    """
    for name, val in (("boxes", boxes), ("tables", tables)):
        if int(val) != val or val < 0:
            raise ConfigurationError(f"add_furniture: {name} must be an integer >= 0, got {val}")
    total = int(boxes) + int(tables)
    if total == 0:
        return room
    gen = as_rng(0 if rng is None else rng)
    kinds = ["box"] * int(boxes) + ["table"] * int(tables)
    placed: list[tuple[FloatArray, float]] = []
    segs: list[FloatArray] = []
    footprints: list[FloatArray] = []
    circles: list[list[float]] = []
    cand = room.positions_inside(400, margin=0.15)
    far = np.hypot(*(cand - room.center).T) >= keep_center_free
    cand = cand[far]
    for kind in kinds:
        for _attempt in range(200):
            if kind == "box":
                hw, hd = gen.uniform(0.15, 0.4), gen.uniform(0.12, 0.3)
                rad = math.hypot(hw, hd)
            else:
                rad = float(gen.uniform(0.2, 0.35))
            if cand.shape[0] == 0:
                break
            p = cand[gen.integers(cand.shape[0])]
            if room.room_world.distance(p[None])[0] < rad + 0.05:
                continue
            if float(np.hypot(*(p - room.center))) < keep_center_free + rad:
                continue
            if any(np.hypot(*(p - q)) < rad + r2 + 0.25 for q, r2 in placed):
                continue
            placed.append((p, rad))
            if kind == "box":
                th = gen.uniform(0, math.pi)
                rot = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
                local = np.array([[-hw, -hd], [hw, -hd], [hw, hd], [-hw, hd]])
                corners = p + local @ rot.T
                segs.extend(polygon_walls(corners, name="furniture box"))
                footprints.append(corners)
            else:
                circles.append([p[0], p[1], rad])
            break
        else:
            raise WorldError(
                f"add_furniture: could not place {total} items in room {room.name!r}"
                " (room too small)"
            )
    furn = World(
        np.array(segs).reshape(-1, 4),
        FURNITURE_HEIGHT,
        MATERIAL_FURNITURE,
        np.array(circles).reshape(-1, 3),
        FURNITURE_HEIGHT,
        MATERIAL_FURNITURE,
    )
    return with_truth(
        _replace(
            room,
            world=room.world + furn,
            n_furniture=room.n_furniture + len(placed),
            obstacles=(*room.obstacles, *footprints),
            obstacle_circles=np.concatenate([room.obstacle_circles, furn.circles]),
        )
    )


def build_room(
    name: str,
    gv: float,
    *,
    lab: bool = True,
    textured: bool = True,
    door: bool | float = False,
    furniture: int = 0,
    tables: int = 0,
    rng: np.random.Generator | int | None = None,
    board_height: float = BOARD_HEIGHT,
) -> Room:
    """Build a room by name with G-V distance ``gv`` [m] (centre to vertex).

    Parameters
    ----------
    name : str
        One of :data:`ROOM_NAMES`: ``triangle``, ``square``, ``pentagon``, ``hexagon``,
        ``octagon`` (regular, centre-to-vertex ``gv``), ``circle`` (radius ``gv``),
        ``rectangle`` (3:2, half-diagonal ``gv``), ``hallway`` (6:1, half-diagonal ``gv``),
        ``l_shaped`` (largest centre-to-corner distance ``gv``).
    gv : float
        G-V distance [m], > 0.
    lab : bool
        Put the room (walls become 0.4 m boards) inside a 12-segment lab, as in the paper's
        real experiment. False: 2.5 m room walls and nothing outside (the paper's Gazebo rooms).
    textured : bool
        Photographs on the tall walls (lab walls, or room walls without a lab). False gives
        plain walls: the paper's failure case for the camera.
    door : bool or float
        A door gap (0.8 m, or this width [m]) in the middle of edge 0.
    furniture, tables : int
        Number of boxes and round tables placed asymmetrically (see :func:`add_furniture`).
    rng : Generator, int or None
        Furniture placement (None: fixed seed 0).
    board_height : float
        Height [m] of the boards when ``lab`` is True.
    """
    key = str(name).lower().replace("-", "_")
    g = check_positive(gv, "gv")
    tall = WALL_HEIGHT
    if key in _POLYGON_SIDES:
        room = regular_polygon_room(
            _POLYGON_SIDES[key], g, door=door, height=tall, textured=textured
        )
    elif key == "circle":
        room = circular_room(g, door=door, height=tall, textured=textured)
    elif key in ("rectangle", "hallway"):
        aspect = RECTANGLE_ASPECT if key == "rectangle" else HALLWAY_ASPECT
        d = 2 * g / math.hypot(aspect, 1.0)
        room = rectangle_room(aspect * d, d, door=door, height=tall, textured=textured, kind=key)
    elif key == "l_shaped":
        unit = l_shaped_room(1.0)
        room = l_shaped_room(g / unit.gv_distance, door=door, height=tall, textured=textured)
    else:
        raise ConfigurationError(
            f"build_room: unknown room name {name!r}; expected one of {', '.join(ROOM_NAMES)}"
        )
    room = add_furniture(room, boxes=furniture, tables=tables, rng=rng)
    if lab:
        room = with_lab(room, board_height=board_height, textured=textured)
    return room
