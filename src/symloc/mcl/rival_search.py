"""Is there another place in the map that explains the scan as well? (a global rival search)

A particle filter can collapse onto a wrong place after a few scans (a corridor that looks like
another corridor, two identical offices) and then holds a single tight hypothesis whose scan
matches the map: nothing inside the filter says that another place would match as well,
because the particles there died. This module answers that question directly, from the map:

1. The evidence is a set of end points ``(M, 2)`` in the robot's current frame (the scans of
   the last few filter updates, chained by odometry, see :class:`symloc.mcl.confidence.ConfidenceJudge`). A
   pose *explains* it to the degree ``score`` = fraction of points that land within ``tol``
   of an obstacle of the map's distance field (the scan-consistency measure of
   :mod:`symloc.mcl.confidence`).
2. **Coarse search** (correlative scan matching, Olson 2009): every free cell on a lattice of
   ``step`` metres, every heading on a lattice of ``angle_step``. A pose within half a lattice
   step of a true match moves a point at range ``r`` by at most ``step / sqrt(2) + r *
   angle_step / 2``; the distance field is 1-Lipschitz, so testing each point against ``tol``
   plus that bound gives an upper bound of the score in the lattice cell: no place that
   explains the evidence can be missed.
3. **Branch and bound**: the lattice cells farther than ``min_distance`` or ``min_angle``
   from the estimate whose bound reaches ``estimate score - margin`` are split into 3 x 3 x 3
   children with a three times tighter bound, and again, until a cell is about one map cell
   wide; the survivors are refined on a one-cell, 1-degree lattice; so is the estimate.
4. The evidence is **ambiguous** when a refined rival scores at least the refined estimate's
   score minus ``margin``, or when more than ``max_candidates`` cells survive a level (or
   ``max_refine`` the last one): uniqueness is only claimed when every place the bound could
   not exclude was checked (weak evidence, such as a bare corridor, is ambiguous by design).

The map is searched through :func:`padded_field`: its grid with a border of unknown cells,
so that end points that fall just off the map (a map whose walls touch its edge) still read
their true distance to the nearest wall and the bound holds.

Before the coarse lattice, positions that no heading can make reach the threshold are left
out (:func:`_may_reach`: a position farther from every obstacle than the points that must pass
reach); the candidates are the same. Above the lattice, its headings are taken three at a
time: each position is first scored at the middle heading of the three with a tolerance wider
by what a turn to the outer ones can move a point (:func:`_group_slack`), and only the
positions that reach the threshold there are scored at the three headings. A lattice pose that
reaches it implies its group does, so the candidates, their order and the report are the
same; about a fifth of the lattice's scoring is saved (the CARMEN logs' searches). The slices
still yield the lattice's pose-point pairs (a budget spreads a search over the same updates);
the level above adds at most a third to them.

Cost: (free area / step^2) x (2 pi / angle_step) x M look-ups, e.g. 500 m^2 at 0.3 m, 6 deg
and 80 points = 27 M look-ups, a tenth of a second to a second; it grows with the map's free
area. :func:`rival_search_steps` yields after each block of poses so that a caller can spread
one search over several scans with a bounded cost per scan
(:class:`symloc.mcl.rival_schedule.RivalSearchRun`), and
:class:`symloc.mcl.confidence.ConfidenceJudge` runs it only when it can change the verdict
(a new track: a jump, a new cluster, a sustained doubt; every ``rival_period`` updates; and
while a place stays ambiguous, with a back-off).
"""

from __future__ import annotations

import math
from collections.abc import Generator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError
from symloc.geometry import wrap_angle
from symloc.grid.distance_field import DistanceField
from symloc.grid.fields import MapFields
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.mcl import kernels
from symloc.mcl.likelihood_field import endpoint_flat_indices

__all__ = [
    "RivalReport",
    "coarse_lattice",
    "find_rival",
    "match_scores",
    "padded_field",
    "rival_search_steps",
]

FloatArray = NDArray[np.float64]

#: Pose-point pairs per block (keeps the temporaries in cache).
_CHUNK = 1 << 18


@dataclass(frozen=True, slots=True)
class RivalReport:
    """Result of :func:`find_rival`.

    Attributes
    ----------
    ambiguous : bool
        A rival pose explains the evidence within ``margin`` of the estimate.
    estimate_score : float
        Best fine score near the estimate (0..1).
    rival_score : float
        Best fine score of a rival (0 when none; the best upper bound when there were too
        many candidates to prove uniqueness: more than ``max_candidates`` at a level or
        ``max_refine`` at the end).
    rival_pose : ndarray of shape (3,) or None
        That rival's pose (map frame).
    n_candidates : int
        Coarse lattice poses whose upper bound reached the threshold (counted until there
        were too many to prove uniqueness: then at least that many).
    n_points : int
        Evidence points used.
    """

    ambiguous: bool
    estimate_score: float
    rival_score: float
    rival_pose: FloatArray | None
    n_candidates: int
    n_points: int


def padded_field(grid: OccupancyGrid | MapFields, max_dist: float) -> DistanceField:
    """Distance field (clipped at ``max_dist`` [m]) of ``grid`` grown by ``max_dist`` of unknown
    cells on every side (same frame, same free cells): the map's shared
    :meth:`~symloc.grid.fields.MapFields.grown` field, computed once per map."""
    return MapFields.of(grid).grown(max_dist)


def match_scores(
    field: DistanceField,
    poses: ArrayLike,
    points: ArrayLike,
    tol: ArrayLike,
    *,
    at_least: float | None = None,
) -> FloatArray:
    """Fraction of ``points (M, 2)`` (robot frame) within ``tol`` of an obstacle, per pose.

    With ``at_least`` only scores ``>= at_least`` are exact: a pose that cannot reach it is
    given up early and reported with some lower value (a search that keeps ``score >=
    at_least`` gets the same poses and scores, sooner).

    Parameters
    ----------
    field : DistanceField
    poses : array of shape (P, 3)
        Robot poses in the map frame.
    points : array of shape (M, 2)
        End points in the robot frame [m].
    tol : float or array of shape (M,)
        Tolerance [m] per point.

    Returns
    -------
    ndarray of shape (P,)
    """
    pz = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    m = pts.shape[0]
    if m == 0:
        return np.zeros(pz.shape[0])
    t = np.broadcast_to(np.asarray(tol, dtype=np.float32), (m,))
    h2, w2 = field.padded.shape
    if h2 * w2 >= 2**31:  # beyond the kernel's 32-bit cell index: NumPy blocks
        r = np.hypot(pts[:, 0], pts[:, 1])
        a = np.arctan2(pts[:, 1], pts[:, 0])
        local = field.grid_frame_poses(pz)
        flat = field.padded.ravel()
        out = np.empty(pz.shape[0])
        step = max(1, _CHUNK // m)
        for s in range(0, pz.shape[0], step):
            idx = endpoint_flat_indices(field, local[s : s + step], r, a)
            out[s : s + step] = np.count_nonzero(flat[idx] <= t, axis=1) / m
        return out
    return _Scorer(field, pts, t).scores(field.grid_frame_poses(pz), at_least)


class _Scorer:
    """The evidence ``points (M, 2)`` [m] (robot frame, M > 0) with one tolerance per point
    ``tol (M,)`` [m], made ready once for :func:`symloc.mcl.kernels.count_within` (end points
    in cell units, float32; the points whose tolerance reaches the field's clip counted once),
    so that a search scoring many blocks of poses against the same points and tolerance
    prepares them once. The field's padded table must have fewer than 2^31 cells."""

    __slots__ = ("bx", "by", "flat", "h2", "inv_res", "m", "pre", "tt", "w2")

    def __init__(self, field: DistanceField, pts: FloatArray, tol: ArrayLike) -> None:
        m = pts.shape[0]
        t = np.broadcast_to(np.asarray(tol, dtype=np.float32), (m,))
        r = np.hypot(pts[:, 0], pts[:, 1])
        a = np.arctan2(pts[:, 1], pts[:, 0])
        self.flat = field.padded.ravel()
        self.h2, self.w2 = field.padded.shape
        # A point whose tolerance reaches the field's clip distance passes at every pose
        # (every value of the table is at most the clip): counted once, not looked up.
        tt_all = np.ascontiguousarray(t, dtype=np.float32)
        sure = tt_all >= np.float32(field.max_dist)
        self.pre = int(np.count_nonzero(sure))
        look = ~sure
        self.inv_res = 1.0 / field.grid.resolution
        self.bx = np.ascontiguousarray(r[look] * np.cos(a[look]) * self.inv_res, dtype=np.float32)
        self.by = np.ascontiguousarray(r[look] * np.sin(a[look]) * self.inv_res, dtype=np.float32)
        self.tt = np.ascontiguousarray(tt_all[look])
        self.m = m

    def scores(self, local: FloatArray, at_least: float | None = None) -> FloatArray:
        """:func:`match_scores` of poses ``local (P, 3)`` already in the grid frame
        (:meth:`~symloc.grid.distance_field.DistanceField.grid_frame_poses`)."""
        local = np.ascontiguousarray(local)
        out = np.empty(local.shape[0])
        need = 0 if at_least is None else needed_count(at_least, self.m)
        flat, w2, h2, inv_res = self.flat, self.w2, self.h2, self.inv_res
        bx, by, tt, pre, m = self.bx, self.by, self.tt, self.pre, self.m

        def run(start: int, stop: int) -> None:
            kernels.count_within(
                flat, w2, h2, local, inv_res, bx, by, tt, pre, m, need, start, stop, out
            )

        kernels.split_over_threads(local.shape[0], local.shape[0] * max(1, bx.size), run)
        return out


def needed_count(at_least: float, m: int) -> int:
    """The smallest count ``c`` of ``m`` points with ``c / m >= at_least`` as the float
    comparison decides it (``m + 1``: none; 0: any)."""
    if at_least <= 0.0:
        return 0
    need = max(0, min(m + 1, math.ceil(at_least * m) - 1))
    while need <= m and need / m < at_least:
        need += 1
    return need


def _may_reach(
    field: DistanceField, xy: FloatArray, reach: FloatArray, at_least: float
) -> NDArray[np.bool_]:
    """Which lattice positions ``(P, 2)`` may score ``at_least`` at some heading.

    A point at range ``r`` that passes with tolerance ``t`` has an obstacle within ``r + t``
    of the position (plus a cell for the end point's and the position's cells), whatever
    the heading; so a position whose own distance to the nearest obstacle exceeds the
    ``need``-th largest of these ``reach [m] (M,)`` cannot have ``need`` points pass at any
    heading, and its lattice scores would all fall below ``at_least``. Leaving it out leaves
    the candidates as they are (a robot in the middle of a hall far from every wall, with
    walls close in its scan, is not there).
    """
    m = reach.size
    need = needed_count(at_least, m)
    if need == 0 or xy.shape[0] == 0:
        return np.ones(xy.shape[0], dtype=np.bool_)
    if need > m:
        return np.zeros(xy.shape[0], dtype=np.bool_)
    res = field.grid.resolution
    limit = float(np.sort(reach)[m - need]) + res
    if limit >= field.max_dist:  # every position reads at most the clip: nothing to exclude
        return np.ones(xy.shape[0], dtype=np.bool_)
    out: NDArray[np.bool_] = field.lookup(xy) <= limit
    return out


#: Consecutive lattice headings grouped under one pose of the level above the lattice.
_GROUP = 3


def _heading_groups(heads: NDArray[np.floating], size: int) -> list[tuple[float, float] | None]:
    """The lattice headings ``heads`` in groups of ``size`` consecutive ones: at each group's
    first heading its ``(centre, spread)`` [rad] (the middle of its first and last heading,
    and the largest turn of a member from it), None at the others."""
    out: list[tuple[float, float] | None] = [None] * heads.size
    for g0 in range(0, heads.size, max(1, size)):
        members = heads[g0 : g0 + max(1, size)]
        centre = 0.5 * (float(members[0]) + float(members[-1]))
        out[g0] = (centre, float(np.max(np.abs(members - centre))))
    return out


def _group_slack(rng_pts: FloatArray, spread: float, res: float) -> FloatArray:
    """How much farther [m] than at a pose turned by at most ``spread`` [rad] a point at range
    ``rng_pts`` may read its distance at the group's centre heading: the end point moves by
    at most ``range * spread``; the two end points' cells' centres are each within half a
    cell diagonal of them (``sqrt(2) res`` for both); the distance field is 1-Lipschitz
    between cell centres. A little more for the float32 arithmetic of the end points and the
    tolerances (about 1e-3 cells), so that the level above the lattice never rejects a
    position one of its headings would keep."""
    slack: FloatArray = (
        rng_pts * spread * (1.0 + 1e-6) + math.sqrt(2.0) * res * 1.01 + 1e-4 * (1.0 + rng_pts)
    )
    return slack


def _unproven(cp: FloatArray, cs: FloatArray, est_score: float, n_cand: int, m: int) -> RivalReport:
    """The ambiguous report when too many candidates ``cp (C, 3)`` (upper bounds ``cs (C,)``)
    are left to prove uniqueness: the best-bounded one as the rival."""
    j = int(cs.argmax())
    return RivalReport(True, est_score, float(cs[j]), cp[j].copy(), n_cand, m)


def _far(
    poses: FloatArray, est: FloatArray, min_distance: float, min_angle: float
) -> NDArray[np.bool_]:
    dxy = np.hypot(poses[:, 0] - est[0], poses[:, 1] - est[1])
    dth = np.abs(wrap_angle(poses[:, 2] - est[2]))
    out: NDArray[np.bool_] = (dxy > min_distance) | (dth > min_angle)
    return out


def _refine(
    field: DistanceField,
    centres: FloatArray,
    points: FloatArray,
    tol: float,
    half_xy: float,
    half_angle: float,
) -> tuple[FloatArray, FloatArray]:
    """Best fine pose and score around each centre ``(C, 3)``: one-cell, 1-degree lattice."""
    res = field.grid.resolution
    n_xy = math.ceil(half_xy / res)
    oxy = np.arange(-n_xy, n_xy + 1) * res
    n_a = math.ceil(half_angle / math.radians(1.0))
    oa = np.arange(-n_a, n_a + 1) * math.radians(1.0)
    gx, gy, ga = np.meshgrid(oxy, oxy, oa, indexing="ij")
    offs = np.column_stack([gx.ravel(), gy.ravel(), ga.ravel()])
    k = offs.shape[0]
    poses = (centres[:, None, :] + offs[None, :, :]).reshape(-1, 3)
    sc = match_scores(field, poses, points, tol).reshape(centres.shape[0], k)
    best = sc.argmax(axis=1)
    rows = np.arange(centres.shape[0])
    bp = poses.reshape(centres.shape[0], k, 3)[rows, best]
    bp[:, 2] = wrap_angle(bp[:, 2])
    return bp, sc[rows, best]


def find_rival(
    field: DistanceField,
    points: ArrayLike,
    estimate: ArrayLike,
    *,
    tol: float,
    step: float = 0.3,
    angle_step: float = math.radians(6.0),
    min_distance: float = 1.0,
    min_angle: float = math.radians(30.0),
    margin: float = 0.1,
    max_points: int = 80,
    max_refine: int = 3000,
    max_candidates: int = 40000,
) -> RivalReport:
    """Search the whole map for a pose that explains ``points`` as well as ``estimate``.

    Runs :func:`rival_search_steps` to the end in one call (same parameters).

    Parameters
    ----------
    field : DistanceField
        The map's distance field; candidate positions are its grid's free cells.
    points : array of shape (M, 2)
        Evidence end points in the robot frame [m] (sub-sampled evenly to ``max_points``).
    estimate : array of shape (3,)
        The filter's pose (map frame).
    tol : float
        Point-to-obstacle tolerance [m] (> 0).
    step, angle_step : float
        Coarse lattice [m], [rad] (> 0).
    min_distance, min_angle : float
        A rival lies farther than this [m] or turned more than this [rad] from the estimate.
    margin : float
        A rival within this score of the estimate's makes the evidence ambiguous.
    max_points : int
        Cap on evidence points.
    max_refine : int
        Most final cells refined exactly; more is reported as ambiguous.
    max_candidates : int
        Most lattice cells split at one branch-and-bound level; more is ambiguous.

    Returns
    -------
    RivalReport
    """
    steps = rival_search_steps(
        field,
        points,
        estimate,
        tol=tol,
        step=step,
        angle_step=angle_step,
        min_distance=min_distance,
        min_angle=min_angle,
        margin=margin,
        max_points=max_points,
        max_refine=max_refine,
        max_candidates=max_candidates,
    )
    while True:
        try:
            next(steps)
        except StopIteration as done:
            report: RivalReport = done.value
            return report


def coarse_lattice(grid: OccupancyGrid, stride: int) -> FloatArray:
    """Centres ``(P, 2)`` [m] of the free cells on a lattice of ``stride`` cells (the rival
    search's coarse positions), computed once per map and kept with its
    :class:`~symloc.grid.fields.MapFields`."""

    def compute(g: OccupancyGrid) -> FloatArray:
        # the free test on the lattice's cells only (the whole map's mask is stride^2 more)
        rows, cols = np.nonzero(g.is_free(g.data[stride // 2 :: stride, stride // 2 :: stride]))
        cells = np.column_stack([rows * stride + stride // 2, cols * stride + stride // 2])
        xy: FloatArray = g.cell_to_world(cells)
        xy.setflags(write=False)
        return xy

    return MapFields.of(grid).derived(f"rival_search.coarse_lattice/{stride}", compute)


def rival_search_steps(
    field: DistanceField,
    points: ArrayLike,
    estimate: ArrayLike,
    *,
    tol: float,
    step: float = 0.3,
    angle_step: float = math.radians(6.0),
    min_distance: float = 1.0,
    min_angle: float = math.radians(30.0),
    margin: float = 0.1,
    max_points: int = 80,
    max_refine: int = 3000,
    max_candidates: int = 40000,
    chunk_pairs: int = 1 << 22,
) -> Generator[int, None, RivalReport]:
    """:func:`find_rival` in slices: a generator that yields the work of each slice and returns
    the :class:`RivalReport` (``StopIteration.value``).

    Each ``next()`` scores at most about ``chunk_pairs`` pose-point pairs (one block of
    lattice poses, or of one branch-and-bound level's children) and yields that number, so a
    caller can spread one search over several scans with a bounded cost per scan
    (:class:`symloc.mcl.rival_schedule.RivalSearchRun`). The slices are the same scores in the
    same order as one call: the report is identical however the work is spread. Parameters as
    :func:`find_rival`; ``chunk_pairs`` (>= 1) is the size of a slice.
    """
    for name, v in (("tol", tol), ("step", step), ("angle_step", angle_step)):
        if not (math.isfinite(v) and v > 0.0):
            raise ConfigurationError(f"{name}: expected a finite value > 0, got {v!r}")
    if not (0.0 <= margin < 1.0):
        raise ConfigurationError(f"margin: expected a value in [0, 1), got {margin!r}")
    if chunk_pairs < 1:
        raise ConfigurationError(f"chunk_pairs: expected an integer >= 1, got {chunk_pairs!r}")
    est = np.asarray(estimate, dtype=np.float64)
    if est.shape != (3,) or not np.all(np.isfinite(est)):
        raise ConfigurationError(f"estimate: expected finite shape (3,), got {est}")
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if pts.shape[0] == 0:
        return RivalReport(True, 0.0, 0.0, None, 0, 0)
    if pts.shape[0] > max_points:
        pts = pts[np.linspace(0, pts.shape[0] - 1, max_points).round().astype(np.intp)]
    m = pts.shape[0]
    grid = field.grid
    res = grid.resolution
    block = max(1, chunk_pairs // m)  # poses per slice
    # Estimate: refined over one coarse cell, like the candidates.
    _, est_sc = _refine(field, est[None], pts, tol, step / 2.0, angle_step / 2.0)
    est_score = float(est_sc[0])
    threshold = est_score - margin

    # Coarse lattice over the free cells.
    stride = max(1, round(step / res))
    xy = coarse_lattice(grid, stride)
    n_h = max(1, math.ceil(2.0 * math.pi / angle_step))
    heads = -math.pi + (np.arange(n_h) + 0.5) * (2.0 * math.pi / n_h)
    da = 2.0 * math.pi / n_h
    rng_pts = np.hypot(pts[:, 0], pts[:, 1])
    loose = tol + stride * res / math.sqrt(2.0) + rng_pts * da / 2.0 + res
    xy = xy[_may_reach(field, xy, rng_pts + loose, threshold)]
    # The first check after the lattice is against max_candidates (max_refine when the
    # lattice cells are already about one map cell wide): once more candidates than that have
    # passed, the answer is "ambiguous" whatever the rest of the lattice holds, so the lattice
    # stops there (the same verdict, much sooner on a map with many look-alike places).
    h_xy, h_a = stride * res / 2.0, da / 2.0
    too_many = max_candidates if h_xy > res else max_refine
    cand_p: list[FloatArray] = []
    cand_s: list[FloatArray] = []
    n_cand = 0
    # The lattice's positions in the grid frame, once (each heading only sets the third
    # column): what match_scores would compute for every block, value for value.
    small = field.padded.size < 2**31
    coarse = _Scorer(field, pts, loose) if small else None
    local = None
    if coarse is not None and field.grid.origin[2] == 0.0:
        local = field.grid_frame_poses(np.column_stack([xy, np.zeros(xy.shape[0])]))
    # The heading groups' level above the lattice (see _heading_groups): per position, may
    # any heading of the current group reach the threshold? Only those positions are scored.
    grouped = coarse is not None and local is not None and _GROUP > 1
    groups = _heading_groups(heads, _GROUP) if grouped else None
    group_ok = np.ones(xy.shape[0], dtype=np.bool_)
    wide: _Scorer | None = None
    centre = 0.0
    for hi, h in enumerate(heads):
        first = groups is not None and groups[hi] is not None
        if first:
            centre, spread = groups[hi]  # type: ignore[index, misc]
            wide = _Scorer(field, pts, loose + _group_slack(rng_pts, spread, res))
        for s0 in range(0, xy.shape[0], block):
            part = xy[s0 : s0 + block]
            if coarse is not None and local is not None:
                lp = local[s0 : s0 + block]
                if wide is None:
                    lp[:, 2] = h
                    sc = coarse.scores(lp, threshold)
                else:
                    if first:
                        lp[:, 2] = centre
                        group_ok[s0 : s0 + block] = wide.scores(lp, threshold) >= threshold
                    ok = group_ok[s0 : s0 + block]
                    lp[:, 2] = h
                    sc = np.full(part.shape[0], -np.inf)
                    if ok.any():
                        sc[ok] = coarse.scores(lp[ok], threshold)
            else:
                poses = np.column_stack([part, np.full(part.shape[0], h)])
                sc = match_scores(field, poses, pts, loose, at_least=threshold)
            keep = sc >= threshold
            if keep.any():
                kp = np.column_stack([part[keep], np.full(int(np.count_nonzero(keep)), h)])
                ks = sc[keep]
                far = _far(kp, est, min_distance - stride * res, min_angle - da)
                cand_p.append(kp[far])
                cand_s.append(ks[far])
                n_cand += int(np.count_nonzero(far))
            yield part.shape[0] * m
            if n_cand > too_many:
                cp, cs = np.concatenate(cand_p), np.concatenate(cand_s)
                return _unproven(cp, cs, est_score, n_cand, m)
    if n_cand == 0:
        return RivalReport(False, est_score, 0.0, None, 0, m)
    cp = np.concatenate(cand_p)
    cs = np.concatenate(cand_s)
    # Branch and bound: split each surviving lattice cell into 3 x 3 x 3 children with a
    # three times tighter bound, until the cells are about one map cell wide.
    while h_xy > res:
        if cp.shape[0] > max_candidates:
            # Too many places the bound cannot exclude: uniqueness is not proven.
            return _unproven(cp, cs, est_score, n_cand, m)
        h_xy, h_a = h_xy / 3.0, h_a / 3.0
        o = np.array([-2.0, 0.0, 2.0])
        gx, gy, ga = np.meshgrid(o * h_xy, o * h_xy, o * h_a, indexing="ij")
        offs = np.column_stack([gx.ravel(), gy.ravel(), ga.ravel()])
        kids = (cp[:, None, :] + offs[None, :, :]).reshape(-1, 3)
        bound = tol + math.sqrt(2.0) * h_xy + rng_pts * h_a + res
        sc = np.empty(kids.shape[0])
        level = _Scorer(field, pts, bound) if small else None
        for s0 in range(0, kids.shape[0], block):
            if level is not None:
                lk = field.grid_frame_poses(kids[s0 : s0 + block])
                sc[s0 : s0 + block] = level.scores(lk, threshold)
            else:
                sc[s0 : s0 + block] = match_scores(
                    field, kids[s0 : s0 + block], pts, bound, at_least=threshold
                )
            yield min(block, kids.shape[0] - s0) * m
        keep = (sc >= threshold) & _far(kids, est, min_distance - h_xy, min_angle - h_a)
        cp, cs = kids[keep], sc[keep]
        if cp.shape[0] == 0:
            return RivalReport(False, est_score, 0.0, None, n_cand, m)
    if cp.shape[0] > max_refine:
        return _unproven(cp, cs, est_score, n_cand, m)
    bp, bs = _refine(field, cp, pts, tol, h_xy, h_a)
    ok = _far(bp, est, min_distance, min_angle)
    if not ok.any():
        return RivalReport(False, est_score, 0.0, None, n_cand, m)
    bp, bs = bp[ok], bs[ok]
    j = int(bs.argmax())
    rival = float(bs[j])
    return RivalReport(rival >= threshold, est_score, rival, bp[j].copy(), n_cand, m)
