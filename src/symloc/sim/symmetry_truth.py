"""The true rotational symmetry of what the lidar sees, computed from the world's geometry.

This is the ground truth that the bench judges symloc's symmetry verdicts against, so it is
computed from the simulated primitives, never declared by whoever built the room:

1. **What the lidar sees.** The primitives strictly taller than the lidar's beam plane
   (:data:`symloc.sim.lidar.LIDAR_MOUNT_HEIGHT`, 0.3 m): walls, furniture, pillars, closed
   doors. People (``MATERIAL_PERSON``) are left out: they move, and the truth is that of the
   static room. **Glass** (``MATERIAL_GLASS``) is left out too (``glass_visible=False``): a
   glass panel is what it physically is, transparent at the lidar's wavelength, so its beam
   passes through (or comes back from the frame now and then, a sensor fault, not geometry).
   **Dark** surfaces (``MATERIAL_DARK``) count: they are there, the lidar only returns less
   often from them.
2. **The room the robot is in.** Given the room's outline, the primitives that lie (even partly)
   inside or on it. If those do not close the outline for the lidar (an open door, room walls
   no taller than the beam plane, a glass section), the lidar sees out through the openings, so
   every lidar-visible primitive outside counts as well (the lab around the paper's room, say).
   That is a superset of what is visible from inside; with the gap itself already in the set it
   changes a verdict only if the outside is less symmetric than the room, and then the lidar
   does see that.
3. **The order.** The primitives' outlines are sampled densely (every ``tolerance / 2``) and
   rotated about their length-weighted centroid (the only point a rotation of a bounded set can
   leave fixed). Order ``k >= 2`` if the rotation by ``2 pi / k`` maps the sample set onto itself
   within ``tolerance`` (both ways, nearest neighbours through a KD-tree), and so does every
   power of it up to a half turn, the largest such ``k <= max_order``; order 0 (continuous) if two rotations by angles that are not rational
   fractions of a turn both do; order 1 otherwise. Only rotations that move the farthest
   primitive by at least 5 tolerances (5 cm at 1 cm) are tested: a smaller rotation slides a
   gently curved outline along itself within the tolerance, so it would "match" anything
   round-ish; finer symmetry than that is continuous within the tolerance, or none.

How *nearly* symmetric a room is (a square with one box: order 1, but a quarter turn leaves
most of it in place) is :func:`near_symmetry_overlap`: the share of the room's lidar-visible
outline that lands on itself when turned by ``2 pi / k``, measured as the localizer measures it
on a map (:func:`symloc.localizer.map_symmetry.map_symmetries` on the ground-truth grid).

The G-V distance is the paper's centre-to-vertex distance: the largest distance from the centre
to a vertex of the room's outline (the radius of a round room), or to the visible geometry when
no outline is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from symloc._checks import check_positive
from symloc.errors import ConfigurationError, WorldError
from symloc.sim.lidar import LIDAR_MOUNT_HEIGHT
from symloc.sim.world import MATERIAL_GLASS, MATERIAL_PERSON, World, points_in_polygon
from symloc.symmetry.order import SymmetryOrder

__all__ = [
    "DEFAULT_TOLERANCE",
    "MAX_ORDER",
    "SymmetryTruth",
    "lidar_symmetry",
    "lidar_visible",
    "near_symmetry_overlap",
    "outline_centroid",
    "outline_samples",
    "rotational_order",
    "truth_order",
]

FloatArray = NDArray[np.float64]

DEFAULT_TOLERANCE = 0.01
"""How far [m] a rotated primitive may lie from the original ones and still count as mapped."""
MAX_ORDER = 256
"""Largest finite order tested; finer symmetry than this is found continuous or not at all."""

# Rotations by these fractions of a turn are not close to k-fold ones for small k, so a set that
# survives both is (within the tolerance) invariant under every rotation.
_IRRATIONAL_TURNS = (math.sqrt(2.0) - 1.0, (math.sqrt(5.0) - 1.0) / 2.0 - 0.5)
_PROBES = 256
_MIN_SHIFT = 5.0


@dataclass(frozen=True, eq=False)
class SymmetryTruth:
    """The true rotational symmetry of a world's lidar-visible geometry.

    Attributes
    ----------
    order : int
        ``k >= 2`` for a k-fold symmetry, 0 for continuous symmetry (a bare round room), 1 for
        none.
    center : ndarray of shape (2,)
        Length-weighted centroid [m] of the primitives counted (the rotation centre when the
        order is not 1).
    gv_distance : float
        Centre to the farthest vertex of the room outline [m] (see the module docstring).
    tolerance : float
        The matching tolerance [m] used.
    open : bool
        True when the room's own primitives leave its outline open to the lidar, so that what
        lies outside was counted too.
    n_walls, n_circles : int
        Number of wall segments and circles counted.
    """

    order: int
    center: FloatArray
    gv_distance: float
    tolerance: float
    open: bool
    n_walls: int
    n_circles: int

    @property
    def symmetric(self) -> bool:
        """True for a k-fold (k >= 2) or continuous symmetry."""
        return self.order != 1

    @property
    def continuous(self) -> bool:
        """True for continuous rotational symmetry (order 0)."""
        return self.order == 0

    @property
    def symmetry_order(self) -> SymmetryOrder:
        """:attr:`order` as the library's :class:`~symloc.symmetry.order.SymmetryOrder`."""
        return truth_order(self.order)


def truth_order(order: int) -> SymmetryOrder:
    """A true order as the simulator writes it (``k >= 1``, 0 for continuous symmetry; e.g.
    ``Room.order``) as a :class:`~symloc.symmetry.order.SymmetryOrder`: the one place that
    reads the simulator's 0."""
    return SymmetryOrder.CIRCLE if int(order) == 0 else SymmetryOrder.finite(int(order))


def lidar_visible(
    world: World, *, plane_height: float = LIDAR_MOUNT_HEIGHT, glass_visible: bool = False
) -> World:
    """The static primitives the lidar sees: taller than ``plane_height`` [m], not people.

    Glass is dropped unless ``glass_visible`` (see the module docstring).
    """
    w = world.visible_above(plane_height)
    drop = [MATERIAL_PERSON] if glass_visible else [MATERIAL_PERSON, MATERIAL_GLASS]
    wk = ~np.isin(np.asarray(w.wall_materials), drop)
    ck = ~np.isin(np.asarray(w.circle_materials), drop)
    return _subset(w, wk, ck)


def _subset(w: World, wk: NDArray[np.bool_], ck: NDArray[np.bool_]) -> World:
    return World(
        w.walls[wk],
        np.asarray(w.wall_heights)[wk],
        np.asarray(w.wall_materials)[wk],
        w.circles[ck],
        np.asarray(w.circle_heights)[ck],
        np.asarray(w.circle_materials)[ck],
        np.asarray(w.wall_tex_u)[wk],
    )


def outline_samples(world: World, spacing: float) -> tuple[FloatArray, NDArray[np.int64]]:
    """Points ``(N, 2)`` [m] every <= ``spacing`` along every wall and circle outline.

    Returns the points and, for each, the index of its primitive (walls first, then circles).
    """
    h = check_positive(spacing, "spacing")
    pts: list[FloatArray] = []
    owner: list[NDArray[np.int64]] = []
    walls = world.walls
    if walls.shape[0]:
        lengths = np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1])
        counts = np.maximum(np.ceil(lengths / h).astype(np.int64), 1) + 1
        idx = np.repeat(np.arange(walls.shape[0]), counts)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        t = (np.arange(int(counts.sum())) - np.repeat(starts, counts)) / np.repeat(
            counts - 1, counts
        )
        a = walls[idx, :2]
        b = walls[idx, 2:]
        pts.append(a + t[:, None] * (b - a))
        owner.append(idx)
    circles = world.circles
    for j, (cx, cy, r) in enumerate(circles):
        m = max(math.ceil(2 * math.pi * r / h), 8)
        ang = 2 * math.pi * np.arange(m) / m
        pts.append(np.column_stack([cx + r * np.cos(ang), cy + r * np.sin(ang)]))
        owner.append(np.full(m, walls.shape[0] + j, dtype=np.int64))
    if not pts:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64)
    return np.concatenate(pts), np.concatenate(owner)


def outline_centroid(world: World) -> FloatArray:
    """Length-weighted centroid ``(2,)`` [m] of every wall segment and circle outline."""
    w = world.walls
    lengths = np.hypot(w[:, 2] - w[:, 0], w[:, 3] - w[:, 1])
    mids = 0.5 * (w[:, :2] + w[:, 2:])
    circ = 2 * math.pi * world.circles[:, 2]
    total = float(lengths.sum() + circ.sum())
    if total <= 0:
        raise WorldError("outline_centroid: the world has no walls and no circles")
    s = (lengths[:, None] * mids).sum(axis=0) + (circ[:, None] * world.circles[:, :2]).sum(axis=0)
    return np.asarray(s / total, dtype=np.float64)


def _rotate(points: FloatArray, center: FloatArray, angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    d = points - center
    return np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]]) + center


@dataclass(frozen=True, eq=False)
class _Matcher:
    """Does a rotated copy of the world lie on the world, within ``tol``, exactly?

    Samples every ``spacing`` along the outlines stand in for the geometry: a point within
    ``tol`` of a sample is within ``tol`` of the geometry; one farther than
    ``tol + spacing / 2`` from every sample is farther than ``tol`` from it; only the points in
    between get an exact distance to the primitives.
    """

    world: World
    pts: FloatArray
    tree: cKDTree
    center: FloatArray
    tol: float
    spacing: float
    probe: FloatArray

    def near(self, points: FloatArray) -> bool:
        """Cheap necessary test: every point within ``tol + spacing / 2`` of a sample."""
        d, _ = self.tree.query(points, distance_upper_bound=self.tol + self.spacing / 2 + 1e-9)
        return bool(np.all(np.isfinite(d)))

    def on(self, points: FloatArray) -> bool:
        """Exact: every point within ``tol`` of the world's outlines."""
        d, _ = self.tree.query(points, distance_upper_bound=self.tol + self.spacing / 2 + 1e-9)
        if not np.all(np.isfinite(d)):
            return False
        unsure = d > self.tol
        if not np.any(unsure):
            return True
        return bool(np.all(self.world.distance(points[unsure]) <= self.tol + 1e-9))

    def maps(self, angle: float) -> bool:
        """The rotation by ``angle`` maps the world onto itself (both ways)."""
        if not self.near(_rotate(self.probe, self.center, angle)):
            return False
        return self.on(_rotate(self.pts, self.center, angle)) and self.on(
            _rotate(self.pts, self.center, -angle)
        )

    def k_fold(self, k: int) -> bool:
        """Every rotation by ``j 2 pi / k`` (j = 1 .. k/2) maps the world onto itself.

        Checking the powers, not only ``2 pi / k``, rejects near-misses such as a 16-gon
        "matching" an 18-fold rotation within the tolerance: the error grows with j for a
        wrong k. Every power is screened on the probe points, the first and the last are
        checked on every sample.
        """
        turns = [2 * math.pi * j / k for j in range(1, k // 2 + 1)]
        if not all(self.near(_rotate(self.probe, self.center, a)) for a in turns):
            return False
        # in full (exactly, both ways) the first power and the one nearest a half turn
        return all(self.maps(a) for a in {turns[0], turns[-1]})


def rotational_order(
    world: World,
    center: ArrayLike | None = None,
    *,
    tolerance: float = DEFAULT_TOLERANCE,
    max_order: int = MAX_ORDER,
) -> tuple[int, FloatArray]:
    """Rotational symmetry order of all of ``world``'s primitives, and the centre used.

    Parameters
    ----------
    world : World
        Every primitive counts (filter first, e.g. with :func:`lidar_visible`).
    center : array of shape (2,), optional
        Rotation centre [m]; default the length-weighted centroid (:func:`outline_centroid`).
    tolerance : float
        Matching tolerance [m], > 0.
    max_order : int
        Largest finite order tested (>= 2).

    Returns
    -------
    order : int
        k >= 2, 0 (continuous) or 1 (none); see the module docstring.
    center : ndarray of shape (2,)
    """
    tol = check_positive(tolerance, "tolerance")
    if int(max_order) != max_order or max_order < 2:
        raise ConfigurationError(f"max_order: expected an integer >= 2, got {max_order}")
    c = outline_centroid(world) if center is None else np.asarray(center, dtype=np.float64)
    spacing = tol / 2.0
    pts, _ = outline_samples(world, spacing)
    tree = cKDTree(pts)
    probe = pts[:: max(1, pts.shape[0] // _PROBES)]
    m = _Matcher(world, pts, tree, c, tol, spacing, probe)
    if all(m.maps(2 * math.pi * f) for f in _IRRATIONAL_TURNS):
        return 0, c
    # A rotation that moves the farthest point by little more than the tolerance "maps" any
    # gently curved outline onto itself; only rotations that move it by >= _MIN_SHIFT
    # tolerances are tested (finer symmetry is continuous within the tolerance, or none).
    reach = float(np.max(np.hypot(*(pts - c).T)))
    ratio = min(1.0, _MIN_SHIFT * tol / (2.0 * reach)) if reach > 0 else 1.0
    k_cap = max(2, min(int(max_order), math.floor(math.pi / math.asin(ratio))))
    # screen every candidate k at once on a few points, then check the survivors in full
    ks = np.arange(k_cap, 1, -1)
    few = pts[:: max(1, pts.shape[0] // 32)] - c
    ang = 2 * np.pi / ks
    cos, sin = np.cos(ang)[:, None], np.sin(ang)[:, None]
    rot = np.stack([cos * few[:, 0] - sin * few[:, 1], sin * few[:, 0] + cos * few[:, 1]], axis=-1)
    d, _ = tree.query(rot.reshape(-1, 2) + c, distance_upper_bound=tol + spacing / 2 + 1e-9)
    survivors = ks[np.all(np.isfinite(d.reshape(ks.size, -1)), axis=1)]
    for k in survivors:
        if m.k_fold(int(k)):
            return int(k), c
    return 1, c


def _room_part(
    visible: World, boundary: FloatArray, tol: float
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], bool]:
    """Which visible walls / circles belong to the room, and whether its outline stays open."""
    spacing = tol / 2.0
    outline = World(np.column_stack([boundary, np.roll(boundary, -1, axis=0)]))
    ring, _ = outline_samples(outline, spacing)
    ring_tree = cKDTree(ring)
    pts, owner = outline_samples(visible, 5 * tol)  # membership needs only a few samples each
    near, _ = ring_tree.query(pts, distance_upper_bound=2 * tol + spacing)
    inside = points_in_polygon(pts, boundary) | np.isfinite(near)
    member = np.zeros(visible.n_walls + visible.n_circles, dtype=bool)
    np.logical_or.at(member, owner, inside)
    wk = member[: visible.n_walls]
    ck = member[visible.n_walls :]
    room = _subset(visible, wk, ck)
    rpts, _ = outline_samples(room, spacing)
    if rpts.shape[0] == 0:
        return wk, ck, True
    d, _ = cKDTree(rpts).query(ring, distance_upper_bound=2 * tol + spacing)
    return wk, ck, bool(not np.all(np.isfinite(d)))


def lidar_symmetry(
    world: World,
    boundary: ArrayLike | None = None,
    *,
    plane_height: float = LIDAR_MOUNT_HEIGHT,
    tolerance: float = DEFAULT_TOLERANCE,
    glass_visible: bool = False,
    max_order: int = MAX_ORDER,
) -> SymmetryTruth:
    """The true rotational symmetry of what the lidar sees in ``world``.

    Parameters
    ----------
    world : World
        The whole static world (room, furniture, lab, ...).
    boundary : array of shape (V, 2), optional
        The outline [m] of the room the robot is in; None counts every visible primitive.
    plane_height : float
        Height [m] of the lidar's beam plane.
    tolerance : float
        Matching tolerance [m] (default 1 cm).
    glass_visible : bool
        Count glass as seen by the lidar (default False: it is transparent to it).
    max_order : int
        Largest finite order tested.

    Returns
    -------
    SymmetryTruth
    """
    tol = check_positive(tolerance, "tolerance")
    visible = lidar_visible(world, plane_height=plane_height, glass_visible=glass_visible)
    if visible.n_walls + visible.n_circles == 0:
        raise WorldError(
            f"lidar_symmetry: nothing in the world is taller than the lidar plane ({plane_height} m)"
        )
    is_open = False
    v: FloatArray | None = None
    if boundary is not None:
        v = np.asarray(boundary, dtype=np.float64).reshape(-1, 2)
        wk, ck, is_open = _room_part(visible, v, tol)
        if not is_open:
            visible = _subset(visible, wk, ck)
    order, center = rotational_order(visible, tolerance=tol, max_order=max_order)
    if v is not None:
        gv = float(np.max(np.hypot(*(v - center).T)))
    else:
        pts, _ = outline_samples(visible, tol)
        gv = float(np.max(np.hypot(*(pts - center).T)))
    return SymmetryTruth(
        order=order,
        center=center,
        gv_distance=gv,
        tolerance=tol,
        open=is_open,
        n_walls=visible.n_walls,
        n_circles=visible.n_circles,
    )


def near_symmetry_overlap(
    world: World,
    boundary: ArrayLike,
    order: int,
    center: ArrayLike | None = None,
    *,
    plane_height: float = LIDAR_MOUNT_HEIGHT,
    resolution: float = 0.05,
    tolerance: float = 0.1,
) -> float:
    """Share of the room's lidar-visible outline that lies on itself turned by ``2 pi / order``.

    The lidar-visible primitives of the room (as :func:`lidar_symmetry` counts them: those in
    or on ``boundary``, everything visible if the outline is open) are rasterised into a
    ground-truth occupancy grid (:func:`symloc.sim.rasterize.world_to_grid`, ``resolution``
    [m]); the overlap is the share of occupied cells that land within ``tolerance`` [m] of an
    occupied cell when turned by ``2 pi / order`` about the best centre near ``center``: the
    measure of :func:`symloc.localizer.map_symmetry.map_symmetries`, the number the localizer
    itself reads off a map ("order 4, overlap 95 %"), but searched near the true centre (the
    localizer searches every centre of the map).

    Parameters
    ----------
    world : World
        The whole static world.
    boundary : array of shape (V, 2)
        The room outline [m].
    order : int
        k >= 2: the rotation tested is ``2 pi / k``.
    center : array of shape (2,), optional
        Where to start the search for the rotation centre [m]: the symmetry centre of the bare
        room when known; default the centroid of the occupied cells.
    plane_height, resolution, tolerance : float
        Lidar plane [m], grid cell [m], match distance [m].

    Returns
    -------
    float
        In [0, 1]; 1 for a room that the rotation maps onto itself (within ``tolerance``).
    """
    from symloc.sim.rasterize import world_to_grid

    if int(order) != order or order < 2:
        raise ConfigurationError(f"order: expected an integer >= 2, got {order}")
    tol = check_positive(tolerance, "tolerance")
    visible = lidar_visible(world, plane_height=plane_height)
    if visible.n_walls + visible.n_circles == 0:
        raise WorldError(
            f"near_symmetry_overlap: nothing in the world is taller than the lidar plane"
            f" ({plane_height} m)"
        )
    v = np.asarray(boundary, dtype=np.float64).reshape(-1, 2)
    wk, ck, is_open = _room_part(visible, v, DEFAULT_TOLERANCE)
    if not is_open:
        visible = _subset(visible, wk, ck)
    grid = world_to_grid(visible, resolution, min_height=plane_height)
    cells = np.argwhere(np.asarray(grid.occupied_mask, dtype=bool))
    pts = np.asarray(grid.cell_to_world(cells), dtype=np.float64)[:, :2]
    tree = cKDTree(pts)
    angle = 2.0 * math.pi / int(order)

    def share(c: FloatArray) -> float:
        d, _ = tree.query(_rotate(pts, c, angle), distance_upper_bound=tol + 1e-9)
        return float(np.mean(np.isfinite(d)))

    c = pts.mean(axis=0) if center is None else np.asarray(center, dtype=np.float64).reshape(2)
    best = share(c)
    for step in (2.0 * tol, tol, 0.5 * tol, 0.25 * tol):
        improved = True
        while improved:
            improved = False
            for dx, dy in ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)):
                cand = c + np.array([dx, dy])
                value = share(cand)
                if value > best + 1e-9:
                    c, best, improved = cand, value, True
    return best
