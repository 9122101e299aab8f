"""Branch-and-bound scan-to-map search: every pose of the map that explains one scan.

A particle filter only proposes the poses its particles happen to reach. This module asks the
map directly, from a single scan: which robot poses ``(x, y, theta)`` explain it, and how well?
It is Cartographer's global localization (``FastCorrelativeScanMatcher2D`` with a full
window; Hess et al. 2016, "Real-Time Loop Closure in 2D LIDAR SLAM", Section V) with a score
that counts beams and a search that lists *every* pose within a margin of the best, not just
the best one.

Score
-----
The scan's valid end points (sub-sampled evenly to ``max_points``, moved into the robot frame
by the laser's mount pose) are placed on the map from a pose; an end point is *explained* when
it lands in a cell whose centre lies within ``hit_tolerance`` of an occupied cell's centre. The
score is the share of end points explained, in [0, 1] (no-return and invalid beams are not
points and do not count).

Search lattice
--------------
Positions: the centre of every free cell of the map (or of a square window of half-width
``linear_window`` around a prior pose). Headings: the full circle (or ``+-angular_window``
around the prior's) at the step that the scan's range implies, as Cartographer picks it: the
step at which the farthest end point (range ``d``, capped at ``step_range``) moves by one cell,
``acos(1 - r^2 / (2 d^2))`` for resolution ``r``, rounded down to divide the circle; or
``angular_step`` if set. Each rotated scan is discretised once: end point ``j`` from cell ``(r,
c)`` at heading ``k`` lands in cell ``(r + dr[k, j], c + dc[k, j])``.

Branch and bound
----------------
:meth:`symloc.grid.fields.MapFields.precomputation_grids` holds, per map, the hit mask and its
max over ``2^d x 2^d`` blocks for ``d = 1..depth``. A node ``(d, k, r, c)`` stands for the
``2^d x 2^d`` positions ``[r, r + 2^d) x [c, c + 2^d)`` at heading ``k``; the sum of level ``d``
at its end points is an upper bound of the number explained from any position in the block
(exact at ``d = 0``). The roots (blocks of ``2^depth`` cells, all headings) are scored and
visited best bound first; each node is split into its four children, which are visited best
first, depth first (Cartographer's ``BranchAndBound``). A block with no free cell in the window
is dropped. The threshold starts at ``min_score`` and rises to ``best - score_margin`` as better
poses are found; a node is pruned only when its bound is below the current threshold, which is
never above the final one.

**Guarantee** (when the result is ``complete``): every lattice pose whose score is at least
``max(min_score, best - score_margin)`` (``best``: the best lattice score) is found; the
exhaustive search over the same lattice (:meth:`GlobalSearch.hits` with ``exhaustive=True``,
plain NumPy) finds exactly the same set, which the tests check.

Distinct poses
--------------
The lattice poses at or above the threshold come in clumps (every cell and heading near a
true pose explains the scan). They are ranked by score, ties broken by the *fit*, the mean
distance [m] from the end points to the nearest occupied cell (each clipped at twice the
tolerance), and thinned by non-maximum suppression: the best remaining pose and every pose
within ``nms_radius`` *and* ``nms_angle`` of it form one candidate, represented by its
member of smallest fit (the centre of the plateau of equal scores). A square room gives four
candidates, one per rotated copy. A candidate is a lattice pose: off by up to half a cell in
x and y, and by a heading step or two (the heading that best makes up for the position's
rounding); the localizer's scan-to-map refinement (:mod:`symloc.mcl.scan_to_map`) takes it
from there.

Cost and cap
------------
A node costs one table look-up per end point. The search stops with the verdict
``incomplete`` (and the poses found so far, which are then *not* a complete list) when it has
evaluated ``max_nodes`` nodes (roots included; the roots alone are counted before any work),
when ``max_seconds`` of wall time have passed (checked every ``_CHUNK_NODES`` nodes), or when
more than ``max_hits`` lattice poses lie within the margin (a long featureless corridor). So a
huge map never blocks its caller: the work is at most ``max_nodes x max_points`` look-ups.
Memory per map: 1 byte per (padded) cell for the pyramid (its levels are the bits of one
array; 2 beyond depth 7), 4 for the integral image and 2 for the clipped distance of the end
points (:meth:`~symloc.grid.fields.MapFields.obstacle_squared_cells`), shared through
:class:`~symloc.grid.fields.MapFields`.

The compiled loops (numba, cached on disk, as :mod:`symloc.mcl.kernels`) are written as plain
Python (``*_py``); the tests run both against the NumPy exhaustive search.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError
from symloc.geometry import as_pose, compose, inverse, transform_points, wrap_angle
from symloc.grid.fields import MapFields
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.grid.precomputation import MAX_DEPTH, PrecomputationGrids
from symloc.mcl import kernels
from symloc.mcl.kernels import numba_jit as _jit
from symloc.scan import LaserScan

__all__ = [
    "GlobalSearch",
    "GlobalSearchConfig",
    "GlobalSearchResult",
    "LatticeHits",
    "PoseCandidate",
    "global_search",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Nodes evaluated per call of the compiled search between two checks of the wall clock.
_CHUNK_NODES = 20_000

_NAME = "GlobalSearchConfig"


# --------------------------------------------------------------------------- settings
def _number(value: object, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConfigurationError(f"{_NAME}.{name}: expected a number, got {value!r}")
    out = float(value)
    if math.isnan(out):
        raise ConfigurationError(f"{_NAME}.{name}: expected a number, got NaN")
    return out


def _integer(value: object, name: str, low: int, high: int | None = None) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ConfigurationError(f"{_NAME}.{name}: expected an integer, got {value!r}")
    if value < low or (high is not None and value > high):
        span = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ConfigurationError(f"{_NAME}.{name}: expected an integer {span}, got {value}")


@dataclass(frozen=True, slots=True)
class GlobalSearchConfig:
    """Settings of the global search (units in brackets).

    Parameters
    ----------
    hit_tolerance : float
        An end point is explained within this distance [m] of an occupied cell (>= 0; cell
        centre to cell centre). Default 0.1 m: two cells of a 5 cm map, about the range noise
        of a low-cost lidar at 5 m plus a map's own error.
    min_score : float
        Least share of end points a listed pose explains, in (0, 1].
    score_margin : float
        Poses within this much of the best score are listed, in [0, 1).
    angular_step : float
        Heading step [rad] in [0, pi / 4]; 0 picks Cartographer's step from the scan's range.
    step_range : float
        Largest range [m] that sets the automatic step (> 0): a 40 m return would otherwise ask
        for 0.07-degree steps.
    linear_window : float
        With a prior pose, positions within this half-width [m] of it in x and y (>= 0, inf:
        the whole map). Ignored without a prior.
    angular_window : float
        With a prior pose, headings within this [rad] of its heading, in [0, pi] (pi: all).
    nms_radius : float
        Two poses closer than this [m] ...
    nms_angle : float
        ... and turned less than this [rad], in [0, pi], are the same candidate.
    max_points : int
        End points used (>= 1), sub-sampled evenly along the scan.
    depth : int
        Levels of the precomputation pyramid (blocks of ``2^depth`` cells), in [0, 12].
    max_nodes : int
        Node budget (>= 1): bound evaluations, roots and leaves included.
    max_seconds : float
        Wall-time budget [s] of one search (> 0, inf: none), checked every ``_CHUNK_NODES``
        nodes per thread; it bounds the latency on a huge or loaded machine, where the node
        budget alone could take longer (the look-ups of a large map miss the caches).
    max_hits : int
        Most lattice poses within the margin held before thinning (>= 1).
    max_candidates : int
        Most distinct poses returned (>= 1); the best ones.
    """

    hit_tolerance: float = 0.1
    min_score: float = 0.5
    score_margin: float = 0.1
    angular_step: float = 0.0
    step_range: float = 15.0
    linear_window: float = math.inf
    angular_window: float = math.pi
    nms_radius: float = 0.5
    nms_angle: float = math.radians(20.0)
    max_points: int = 200
    depth: int = 7
    max_nodes: int = 5_000_000
    max_seconds: float = 5.0
    max_hits: int = 200_000
    max_candidates: int = 32

    def __post_init__(self) -> None:
        def finite(name: str, low: float, high: float, *, open_low: bool = False) -> None:
            v = _number(getattr(self, name), name)
            bad = not math.isfinite(v) or v > high or (v <= low if open_low else v < low)
            if bad:
                lo = "(" if open_low else "["
                raise ConfigurationError(
                    f"{_NAME}.{name}: expected a finite value in {lo}{low:g}, {high:g}], got {v}"
                )

        finite("hit_tolerance", 0.0, 10.0)
        finite("min_score", 0.0, 1.0, open_low=True)
        v = _number(self.score_margin, "score_margin")
        if not 0.0 <= v < 1.0:
            raise ConfigurationError(
                f"{_NAME}.score_margin: expected a value in [0, 1), got {self.score_margin}"
            )
        finite("angular_step", 0.0, math.pi / 4.0)
        finite("step_range", 0.0, 1e4, open_low=True)
        v = _number(self.linear_window, "linear_window")
        if v < 0.0:
            raise ConfigurationError(
                f"{_NAME}.linear_window: expected a value >= 0 m (inf: the whole map), got {v}"
            )
        finite("angular_window", 0.0, math.pi)
        finite("nms_radius", 0.0, 1e4)
        finite("nms_angle", 0.0, math.pi)
        _integer(self.max_points, "max_points", 1)
        _integer(self.depth, "depth", 0, MAX_DEPTH)
        _integer(self.max_nodes, "max_nodes", 1)
        v = _number(self.max_seconds, "max_seconds")
        if not v > 0.0:
            raise ConfigurationError(
                f"{_NAME}.max_seconds: expected a value > 0 s (inf: no limit), got {v}"
            )
        _integer(self.max_hits, "max_hits", 1)
        _integer(self.max_candidates, "max_candidates", 1)


# --------------------------------------------------------------------------- results
@dataclass(frozen=True, slots=True)
class PoseCandidate:
    """One distinct pose that explains the scan.

    Attributes
    ----------
    pose : ndarray of shape (3,)
        The robot (base) pose x [m], y [m], theta [rad] in the map frame: a free cell's centre
        and a lattice heading.
    score : float
        Share of the end points explained (0..1).
    n_explained : int
        End points explained.
    fit : float
        Mean distance [m] of the end points to the nearest occupied cell, each clipped at twice
        the hit tolerance (the tie-break among equal scores; smaller is closer).
    """

    pose: FloatArray
    score: float
    n_explained: int
    fit: float


@dataclass(frozen=True, slots=True)
class GlobalSearchResult:
    """What :meth:`GlobalSearch.search` found.

    Attributes
    ----------
    candidates : tuple of PoseCandidate
        Distinct poses scoring at least :attr:`threshold`, best first (at most
        ``max_candidates``).
    complete : bool
        True when the whole lattice was searched: then no pose of the lattice scoring at least
        :attr:`threshold` is missing (up to the thinning). False when a budget stopped it or the
        scan has no points (see :attr:`reason`); the candidates are then only those found.
    reason : str
        Why the search is incomplete ("" when complete).
    best_score : float
        Best lattice score found (0 when none reached ``min_score``).
    threshold : float
        ``max(min_score, best_score - score_margin)``.
    n_points : int
        End points used.
    angular_step : float
        Heading step [rad].
    n_headings : int
    n_positions : int
        Free cells in the search window.
    n_nodes : int
        Bound evaluations (roots and leaves included).
    n_hits : int
        Lattice poses at or above the threshold before thinning.
    n_distinct : int
        Distinct poses after thinning, counted up to ``max_candidates + 1``: more than
        ``len(candidates)`` means the list is truncated (:attr:`truncated`).
    seconds : float
        Wall time [s] of the search (the map's precomputation excluded).
    """

    candidates: tuple[PoseCandidate, ...]
    complete: bool
    reason: str
    best_score: float
    threshold: float
    n_points: int
    angular_step: float
    n_headings: int
    n_positions: int
    n_nodes: int
    n_hits: int
    n_distinct: int
    seconds: float

    @property
    def truncated(self) -> bool:
        """More distinct poses than ``max_candidates`` explain the scan (only the best are
        listed)."""
        return self.n_distinct > len(self.candidates)

    @property
    def verdict(self) -> str:
        """``"complete"`` or ``"incomplete"``."""
        return "complete" if self.complete else "incomplete"


@dataclass(frozen=True, slots=True)
class LatticeHits:
    """Lattice poses at or above the threshold, before thinning (:meth:`GlobalSearch.hits`).

    Attributes
    ----------
    heading, row, col : ndarray of shape (L,), int64
        Heading index (into :attr:`headings`) and cell of each pose.
    count : ndarray of shape (L,), int64
        End points explained.
    fit : ndarray of shape (L,)
        Mean clipped distance [m] (see :attr:`PoseCandidate.fit`).
    need : int
        The threshold in end points: ``ceil(max(min_score, best - margin) * n_points)``.
    best : int
        Best count found.
    n_points : int
    headings : ndarray of shape (K,)
        Heading [rad] of each index in the grid frame.
    n_nodes : int
    complete : bool
    reason : str
    n_positions : int
    """

    heading: IntArray
    row: IntArray
    col: IntArray
    count: IntArray
    fit: FloatArray
    need: int
    best: int
    n_points: int
    headings: FloatArray
    n_nodes: int
    complete: bool
    reason: str
    n_positions: int

    def key_set(self) -> set[tuple[int, int, int, int]]:
        """``{(heading, row, col, count)}``: the hits as a set (for comparisons)."""
        return {
            (int(k), int(r), int(c), int(n))
            for k, r, c, n in zip(self.heading, self.row, self.col, self.count, strict=True)
        }


# --------------------------------------------------------------------------- kernels
def need_py(best: int, m: int, min_score: float, margin: float) -> int:
    """End points a pose must explain: ``ceil(max(min_score m, best - margin m))`` (at least 1).

    A tiny slack absorbs the rounding of ``score * m`` (0.3 * 10 must give 3, not 4).
    """
    t = max(min_score * m, best - margin * m)
    return max(1, math.ceil(t - 1e-9))


_need = _jit(need_py)


def block_count_py(
    bits: NDArray[np.unsignedinteger],
    bit: int,
    pad: int,
    drk: NDArray[np.int32],
    dck: NDArray[np.int32],
    r: int,
    c: int,
) -> int:
    """Sum of level ``bit`` of the pyramid ``bits`` at the end points ``(r + drk[j], c +
    dck[j])`` (index shifted by ``pad``; outside the array reads 0): the bound of the block
    whose corner is ``(r, c)``."""
    h2, w2 = bits.shape
    s = 0
    for j in range(drk.shape[0]):
        i = r + drk[j] + pad
        q = c + dck[j] + pad
        if 0 <= i < h2 and 0 <= q < w2:
            s += (bits[i, q] >> bit) & 1
    return s


_block_count = _jit(block_count_py)


def free_in_py(
    integral: NDArray[np.int32], box: NDArray[np.int64], r0: int, r1: int, c0: int, c1: int
) -> int:
    """Free cells of rows ``[r0, r1)``, columns ``[c0, c1)`` inside ``box = (R0, R1, C0, C1)``."""
    a0 = max(r0, box[0])
    a1 = min(r1, box[1])
    b0 = max(c0, box[2])
    b1 = min(c1, box[3])
    if a0 >= a1 or b0 >= b1:
        return 0
    return (
        int(integral[a1, b1])
        - int(integral[a0, b1])
        - int(integral[a1, b0])
        + int(integral[a0, b0])
    )


_free_in = _jit(free_in_py)


def root_bounds_py(
    bits: NDArray[np.unsignedinteger],
    bit: int,
    pad: int,
    dr: NDArray[np.int32],
    dc: NDArray[np.int32],
    rk: IntArray,
    rr: IntArray,
    rc: IntArray,
    out: IntArray,
) -> None:
    """``out[i]``: the bound of root ``i`` (heading ``rk[i]``, corner ``(rr[i], rc[i])``)."""
    for i in range(rk.shape[0]):
        k = rk[i]
        out[i] = _block_count(bits, bit, pad, dr[k], dc[k], rr[i], rc[i])


root_bounds = _jit(root_bounds_py)


def branch_and_bound_py(
    bits: NDArray[np.unsignedinteger],
    depth: int,
    pad: int,
    dr: NDArray[np.int32],
    dc: NDArray[np.int32],
    integral: NDArray[np.int32],
    box: IntArray,
    dist_k: NDArray[np.uint16],
    dist_of_k: FloatArray,
    min_score: float,
    margin: float,
    roots_k: IntArray,
    roots_r: IntArray,
    roots_c: IntArray,
    roots_b: IntArray,
    start: int,
    chunk_nodes: int,
    max_nodes: int,
    state: IntArray,
    shared: IntArray,
    hk: IntArray,
    hr: IntArray,
    hc: IntArray,
    hn: IntArray,
    hd: FloatArray,
) -> int:
    """Depth-first branch and bound over the roots ``start, start + 1, ...`` (sorted by bound,
    best first); returns the next root to visit (``len(roots)`` when done).

    ``state = [best count, nodes evaluated, hits held, flag]`` carries over between calls; the
    flag is set to 1 when a node beyond ``max_nodes`` would be evaluated and to 2 when the hit buffer ``hk, hr, hc,
    hn, hd`` (heading, row, col, count, mean clipped distance) is full of poses within the
    margin. Returns after the root during which ``chunk_nodes`` more nodes were evaluated.
    ``shared[0]`` is the best count found by any thread searching other headings: read before
    every node and raised here, it only ever lifts the threshold to one that some pose of the
    lattice reaches (a stale read prunes less, never wrongly).
    """
    m = dr.shape[1]
    h_map = dist_k.shape[0]
    w_map = dist_k.shape[1]
    dist_cap = dist_of_k[-1]
    cap = hk.shape[0]
    n_roots = roots_k.shape[0]
    size = 3 * depth + 2
    sd = np.empty(size, dtype=np.int64)
    sr = np.empty(size, dtype=np.int64)
    sc = np.empty(size, dtype=np.int64)
    sb = np.empty(size, dtype=np.int64)
    kr = np.empty(4, dtype=np.int64)
    kc = np.empty(4, dtype=np.int64)
    kb = np.empty(4, dtype=np.int64)
    best = state[0]
    nodes = state[1]
    nh = state[2]
    top = max(best, shared[0])
    need = _need(top, m, min_score, margin)
    nodes0 = nodes
    i = start
    while i < n_roots:
        sh = shared[0]
        if sh > top:
            top = sh
            need = _need(top, m, min_score, margin)
        if roots_b[i] < need:  # sorted: no later root can reach the threshold
            i = n_roots
            break
        k = roots_k[i]
        drk = dr[k]
        dck = dc[k]
        sp = 0
        sd[0] = depth
        sr[0] = roots_r[i]
        sc[0] = roots_c[i]
        sb[0] = roots_b[i]
        sp = 1
        while sp > 0:
            sh = shared[0]
            if sh > top:
                top = sh
                need = _need(top, m, min_score, margin)
            sp -= 1
            d = sd[sp]
            r = sr[sp]
            c = sc[sp]
            b = sb[sp]
            if b < need:
                continue
            if d == 0:  # a lattice pose: b is its exact count
                s = 0.0
                for j in range(m):
                    rr = r + drk[j]
                    cc = c + dck[j]
                    v = dist_cap
                    if 0 <= rr < h_map and 0 <= cc < w_map:
                        v = dist_of_k[dist_k[rr, cc]]
                    s += v
                if nh == cap:  # drop what the risen threshold excludes
                    w = 0
                    for q in range(nh):
                        if hn[q] >= need:
                            hk[w] = hk[q]
                            hr[w] = hr[q]
                            hc[w] = hc[q]
                            hn[w] = hn[q]
                            hd[w] = hd[q]
                            w += 1
                    nh = w
                    if nh == cap:
                        state[0] = best
                        state[1] = nodes
                        state[2] = nh
                        state[3] = 2
                        return i
                hk[nh] = k
                hr[nh] = r
                hc[nh] = c
                hn[nh] = b
                hd[nh] = s / m
                nh += 1
                if b > best:
                    best = b
                    if b > shared[0]:
                        shared[0] = b
                    if b > top:
                        top = b
                        need = _need(top, m, min_score, margin)
                continue
            h = 1 << (d - 1)
            nk = 0
            for q in range(4):
                cr = r + (q & 1) * h
                cq = c + (q >> 1) * h
                if _free_in(integral, box, cr, cr + h, cq, cq + h) == 0:
                    continue
                if nodes >= max_nodes:
                    state[0] = best
                    state[1] = nodes
                    state[2] = nh
                    state[3] = 1
                    return i
                cb = _block_count(bits, d - 1, pad, drk, dck, cr, cq)
                nodes += 1
                if cb >= need:
                    # insertion sort, ascending by bound
                    p = nk
                    while p > 0 and kb[p - 1] > cb:
                        kr[p] = kr[p - 1]
                        kc[p] = kc[p - 1]
                        kb[p] = kb[p - 1]
                        p -= 1
                    kr[p] = cr
                    kc[p] = cq
                    kb[p] = cb
                    nk += 1
            for p in range(nk):  # the best child ends on top of the stack
                sd[sp] = d - 1
                sr[sp] = kr[p]
                sc[sp] = kc[p]
                sb[sp] = kb[p]
                sp += 1
        i += 1
        if nodes - nodes0 >= chunk_nodes:
            break
    state[0] = best
    state[1] = nodes
    state[2] = nh
    return i


branch_and_bound = _jit(branch_and_bound_py)


# --------------------------------------------------------------------------- the search
def _clipped_distance(
    fields: MapFields, cap: float
) -> tuple[NDArray[np.unsignedinteger], FloatArray]:
    """The distance [m] of each cell to the nearest occupied cell, clipped at ``cap`` [m]:
    ``(codes, table)`` with ``codes`` ``(H, W)`` (uint16) indexing ``table`` (float64), whose
    last entry is ``cap``; ``table[codes]`` equals ``min(obstacle_distance, cap)`` value for
    value.

    From :meth:`~symloc.grid.fields.MapFields.obstacle_squared_cells` (2 bytes per cell)
    when ``cap`` is within its reach; else (a hit tolerance of over 127 cells, or a map
    without an occupied cell) from the distinct values of the float64 field."""
    if cap < fields.obstacle_reach() and fields.grid.occupied_mask.any():
        k, metres = fields.obstacle_squared_cells()
        return k, np.minimum(metres, cap)
    values, codes = np.unique(np.minimum(fields.obstacle_distance(), cap), return_inverse=True)
    table = np.append(values, cap)
    dtype = np.uint16 if table.size <= 1 << 16 else np.uint32
    return codes.reshape(fields.grid.data.shape).astype(dtype), table


@dataclass(frozen=True, slots=True)
class _Lattice:
    points: FloatArray  # (M, 2) robot frame, sub-sampled
    headings: FloatArray  # (K,) grid frame
    dr: NDArray[np.int32]  # (K, M)
    dc: NDArray[np.int32]
    box: IntArray  # (4,) R0, R1, C0, C1
    step: float


class GlobalSearch:
    """The branch-and-bound global search on one map (its precomputation shared per map).

    Parameters
    ----------
    grid : OccupancyGrid or MapFields
        The map; its pyramid comes from :meth:`MapFields.precomputation_grids` (built on the
        first search of the map with these ``hit_tolerance`` and ``depth``, then shared).
    config : GlobalSearchConfig, optional
    """

    def __init__(
        self, grid: OccupancyGrid | MapFields, config: GlobalSearchConfig | None = None
    ) -> None:
        cfg = GlobalSearchConfig() if config is None else config
        if not isinstance(cfg, GlobalSearchConfig):
            raise ConfigurationError(
                f"config: expected a GlobalSearchConfig, got {type(cfg).__name__}"
            )
        self.fields = MapFields.of(grid)
        self.config = cfg
        self.grid = self.fields.grid
        self.pyramid: PrecomputationGrids = self.fields.precomputation_grids(
            cfg.hit_tolerance, cfg.depth
        )
        # the end points' distance, clipped at dist_cap: 2 bytes per cell and a table
        self.dist_cap = 2.0 * max(cfg.hit_tolerance, self.grid.resolution)
        self.dist_k, self.dist_of_k = _clipped_distance(self.fields, self.dist_cap)

    # ----------------------------------------------------------------- inputs
    def scan_points(self, scan: LaserScan, laser_pose: ArrayLike | None = None) -> FloatArray:
        """The scan's valid end points ``(M, 2)`` in the robot frame (``laser_pose``: the
        laser's mount pose on the robot, ``base_from_laser``; default the base origin)."""
        if not isinstance(scan, LaserScan):
            raise ConfigurationError(f"scan: expected a LaserScan, got {type(scan).__name__}")
        pts = scan.to_points().points
        if laser_pose is None:
            return np.asarray(pts, dtype=np.float64)
        mount = as_pose(laser_pose, "laser_pose")
        if mount.shape != (3,):
            raise ConfigurationError(f"laser_pose: expected shape (3,), got {mount.shape}")
        if pts.shape[0] == 0:
            return np.zeros((0, 2))
        return transform_points(mount, pts)

    def _lattice(self, points: ArrayLike, prior: ArrayLike | None) -> _Lattice:
        cfg = self.config
        try:
            pts = np.asarray(points, dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise ConfigurationError("points: cannot convert to a float array") from err
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ConfigurationError(f"points: expected shape (M, 2), got {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise ConfigurationError("points: contains NaN or infinite values")
        if pts.shape[0] > cfg.max_points:
            pts = pts[np.linspace(0, pts.shape[0] - 1, cfg.max_points).round().astype(np.intp)]
        g = self.grid
        res = g.resolution
        # heading step: Cartographer's, from the farthest end point
        step = cfg.angular_step
        if step == 0.0:
            d = float(np.hypot(pts[:, 0], pts[:, 1]).max()) if pts.shape[0] else res
            d = min(max(d, res), cfg.step_range)
            step = math.acos(1.0 - res * res / (2.0 * d * d))
        n_full = max(1, math.ceil(2.0 * math.pi / step - 1e-9))
        h, w = g.height, g.width
        box = np.array([0, h, 0, w], dtype=np.int64)
        if prior is None or cfg.angular_window >= math.pi:
            step = 2.0 * math.pi / n_full
            base = -math.pi if prior is None else 0.0
            headings = base + step * np.arange(n_full)
        if prior is not None:
            p = as_pose(prior, "prior")
            if p.shape != (3,):
                raise ConfigurationError(f"prior: expected shape (3,), got {p.shape}")
            pg = compose(inverse(g.origin), p)
            if cfg.angular_window >= math.pi:
                headings = wrap_angle(pg[2] + headings)
            else:
                n = math.floor(cfg.angular_window / step + 1e-9)
                headings = wrap_angle(pg[2] + step * np.arange(-n, n + 1))
            lw = cfg.linear_window
            if math.isfinite(lw):
                u = pg[:2] / res - 0.5  # cell coordinates of the prior (centre = integer)
                box = np.array(
                    [
                        max(0, math.ceil(u[1] - lw / res - 1e-9)),
                        min(h, math.floor(u[1] + lw / res + 1e-9) + 1),
                        max(0, math.ceil(u[0] - lw / res - 1e-9)),
                        min(w, math.floor(u[0] + lw / res + 1e-9) + 1),
                    ],
                    dtype=np.int64,
                )
        heads: FloatArray = np.asarray(headings, dtype=np.float64)
        cth, sth = np.cos(heads)[:, None], np.sin(heads)[:, None]
        x = (cth * pts[None, :, 0] - sth * pts[None, :, 1]) / res
        y = (sth * pts[None, :, 0] + cth * pts[None, :, 1]) / res
        dc = np.floor(x + 0.5).astype(np.int32)
        dr = np.floor(y + 0.5).astype(np.int32)
        return _Lattice(pts, heads, dr, dc, box, float(step))

    def _n_positions(self, box: IntArray) -> int:
        return self.pyramid.free_count(int(box[0]), int(box[1]), int(box[2]), int(box[3]))

    # ----------------------------------------------------------------- searches
    def hits(
        self, points: ArrayLike, *, prior: ArrayLike | None = None, exhaustive: bool = False
    ) -> LatticeHits:
        """Every lattice pose scoring at least ``max(min_score, best - score_margin)``.

        ``points (M, 2)``: end points in the robot frame [m]. ``exhaustive`` scores every
        lattice pose with plain NumPy instead (the reference the branch and bound is tested
        against; no budget).
        """
        lat = self._lattice(points, prior)
        if exhaustive:
            return self._exhaustive(lat)
        return self._branch_and_bound(lat, time.perf_counter())

    def _empty_hits(self, lat: _Lattice, nodes: int, complete: bool, reason: str) -> LatticeHits:
        z = np.zeros(0, dtype=np.int64)
        m = lat.points.shape[0]
        need = need_py(0, m, self.config.min_score, self.config.score_margin) if m else 1
        return LatticeHits(
            z, z, z, z, np.zeros(0), need, 0, m, lat.headings, nodes, complete, reason,
            self._n_positions(lat.box),
        )  # fmt: skip

    def _branch_and_bound(self, lat: _Lattice, t0: float) -> LatticeHits:
        cfg = self.config
        pyr = self.pyramid
        m = lat.points.shape[0]
        if m == 0:
            return self._empty_hits(lat, 0, False, "the scan has no valid end points")
        box = lat.box
        depth, s = pyr.depth, pyr.pad
        # roots: blocks of 2^depth cells over the window that hold a free cell, every heading
        r0s = np.arange(int(box[0]), int(box[1]), s)
        c0s = np.arange(int(box[2]), int(box[3]), s)
        blocks = [
            (r, c)
            for r in r0s
            for c in c0s
            if pyr.free_count(
                max(int(r), int(box[0])),
                min(int(r) + s, int(box[1])),
                max(int(c), int(box[2])),
                min(int(c) + s, int(box[3])),
            )
            > 0
        ]
        n_k = lat.headings.size
        n_roots = len(blocks) * n_k
        if n_roots == 0:
            return self._empty_hits(lat, 0, True, "")
        if n_roots > cfg.max_nodes:
            return self._empty_hits(
                lat, 0, False, f"node budget: {n_roots} roots exceed max_nodes={cfg.max_nodes}"
            )
        bl = np.asarray(blocks, dtype=np.int64).reshape(-1, 2)
        n_b = bl.shape[0]
        need0 = need_py(0, m, cfg.min_score, cfg.score_margin)
        parts: dict[int, tuple[IntArray, IntArray, IntArray, IntArray, IntArray, FloatArray, str]]
        parts = {}
        shared = np.zeros(1, dtype=np.int64)  # the best count of any thread so far

        def work(k0: int, k1: int) -> None:
            """Search the headings ``[k0, k1)`` with their own hit buffer and share of the
            node budget; the best count found so far is shared (a thread's threshold is never
            above the final one: the bound stays admissible)."""
            budget = max(1, cfg.max_nodes * (k1 - k0) // n_k)
            rk = np.repeat(np.arange(k0, k1, dtype=np.int64), n_b)
            rr = np.tile(bl[:, 0], k1 - k0)
            rc = np.tile(bl[:, 1], k1 - k0)
            rb = np.empty(rk.size, dtype=np.int64)
            state = np.array([0, rk.size, 0, 0], dtype=np.int64)
            cap = cfg.max_hits
            hk = np.empty(cap, dtype=np.int64)
            hr = np.empty(cap, dtype=np.int64)
            hc = np.empty(cap, dtype=np.int64)
            hn = np.empty(cap, dtype=np.int64)
            hd = np.empty(cap, dtype=np.float64)
            reason = ""
            chunk = max(1, _CHUNK_NODES)
            for q in range(0, rk.size, chunk):
                sl = slice(q, q + chunk)
                root_bounds(pyr.bits, depth, s, lat.dr, lat.dc, rk[sl], rr[sl], rc[sl], rb[sl])
                if q + chunk < rk.size and time.perf_counter() - t0 > cfg.max_seconds:
                    reason = f"time budget: max_seconds={cfg.max_seconds:g} s passed"
                    break
            i = 0
            if not reason:
                keep = rb >= need0
                rk, rr, rc, rb = rk[keep], rr[keep], rc[keep], rb[keep]
                order = np.argsort(-rb, kind="stable")
                rk, rr, rc, rb = rk[order], rr[order], rc[order], rb[order]
            while not reason and i < rk.size:
                i = branch_and_bound(
                    pyr.bits, depth, s, lat.dr, lat.dc, pyr.free_integral, box, self.dist_k,
                    self.dist_of_k, cfg.min_score, cfg.score_margin, rk, rr, rc, rb, i, chunk, budget,
                    state, shared, hk, hr, hc, hn, hd,
                )  # fmt: skip
                if state[3] == 1:
                    reason = f"node budget: max_nodes={cfg.max_nodes} evaluated"
                elif state[3] == 2:
                    reason = f"more than max_hits={cap} lattice poses within the margin"
                elif i < rk.size and time.perf_counter() - t0 > cfg.max_seconds:
                    reason = f"time budget: max_seconds={cfg.max_seconds:g} s passed"
            nh = int(state[2])
            parts[k0] = (state, hk[:nh], hr[:nh], hc[:nh], hn[:nh], hd[:nh], reason)

        kernels.split_over_threads(n_k, n_roots * m, work)
        runs = [parts[k] for k in sorted(parts)]
        best = max(int(p[0][0]) for p in runs)
        nodes = sum(int(p[0][1]) for p in runs)
        reasons = [p[6] for p in runs if p[6]]
        need = need_py(best, m, cfg.min_score, cfg.score_margin)
        hk, hr, hc, hn = (np.concatenate([p[j] for p in runs]) for j in (1, 2, 3, 4))
        hd = np.concatenate([p[5] for p in runs])
        sel = np.flatnonzero(hn >= need)
        if sel.size > cfg.max_hits:
            # each thread filled its own buffer: keep the best max_hits of them all
            sel = sel[np.argsort(-hn[sel], kind="stable")[: cfg.max_hits]]
            sel.sort()
            if not reasons:
                reasons = [f"more than max_hits={cfg.max_hits} lattice poses within the margin"]
        return LatticeHits(
            hk[sel], hr[sel], hc[sel], hn[sel], hd[sel], need, best, m, lat.headings, nodes,
            not reasons, reasons[0] if reasons else "", self._n_positions(box),
        )  # fmt: skip

    def _exhaustive(self, lat: _Lattice) -> LatticeHits:
        cfg = self.config
        m = lat.points.shape[0]
        if m == 0:
            return self._empty_hits(lat, 0, False, "the scan has no valid end points")
        box = lat.box
        free = np.zeros((self.grid.height, self.grid.width), dtype=bool)
        free[box[0] : box[1], box[2] : box[3]] = self.grid.free_mask[
            box[0] : box[1], box[2] : box[3]
        ]
        rows, cols = np.nonzero(free)
        bits = self.pyramid.bits
        pad = self.pyramid.pad
        h2, w2 = bits.shape
        cap = self.dist_cap
        counts = np.zeros((lat.headings.size, rows.size), dtype=np.int64)
        fits = np.zeros((lat.headings.size, rows.size))
        for k in range(lat.headings.size):
            ri = rows[:, None] + lat.dr[k][None, :]
            ci = cols[:, None] + lat.dc[k][None, :]
            inside = (ri + pad >= 0) & (ri + pad < h2) & (ci + pad >= 0) & (ci + pad < w2)
            v = bits[np.where(inside, ri + pad, 0), np.where(inside, ci + pad, 0)] & 1
            counts[k] = np.where(inside, v, 0).sum(axis=1)
            on_map = (ri >= 0) & (ri < self.grid.height) & (ci >= 0) & (ci < self.grid.width)
            dv = self.dist_of_k[self.dist_k[np.where(on_map, ri, 0), np.where(on_map, ci, 0)]]
            fits[k] = np.where(on_map, dv, cap).sum(axis=1) / m
        best = int(counts.max()) if counts.size else 0
        need0 = need_py(0, m, cfg.min_score, cfg.score_margin)
        if best < need0:
            best = 0
        need = need_py(best, m, cfg.min_score, cfg.score_margin)
        kk, jj = np.nonzero(counts >= need)
        return LatticeHits(
            kk.astype(np.int64), rows[jj].astype(np.int64), cols[jj].astype(np.int64),
            counts[kk, jj], fits[kk, jj], need, best, m, lat.headings,
            int(counts.size), True, "", int(rows.size),
        )  # fmt: skip

    def candidates(self, hits: LatticeHits) -> tuple[list[PoseCandidate], int]:
        """Thin the hits to distinct poses, best first: ``(the first max_candidates, how many
        distinct poses there are, counted up to max_candidates + 1)``."""
        cfg = self.config
        if hits.count.size == 0:
            return [], 0
        res = self.grid.resolution
        local = np.column_stack(
            [(hits.col + 0.5) * res, (hits.row + 0.5) * res, hits.headings[hits.heading]]
        )
        poses = compose(self.grid.origin, local)
        order = np.lexsort((hits.fit, -hits.count))
        poses, cnt, fit = poses[order], hits.count[order], hits.fit[order]
        alive = np.ones(cnt.size, dtype=bool)
        picked: list[int] = []
        while len(picked) <= cfg.max_candidates:  # one more tells that there are more
            idx = np.flatnonzero(alive)
            if idx.size == 0:
                break
            j = int(idx[0])  # the best remaining pose leads a new candidate ...
            near = (
                np.hypot(poses[idx, 0] - poses[j, 0], poses[idx, 1] - poses[j, 1]) <= cfg.nms_radius
            ) & (np.abs(wrap_angle(poses[idx, 2] - poses[j, 2])) <= cfg.nms_angle)
            near[0] = True
            members = idx[near]
            # ... represented by its member closest to the walls (the plateau of equal
            # counts around a true pose is a few cells wide; the fit singles out its centre)
            picked.append(int(members[np.argmin(fit[members])]))
            alive[members] = False
        n_distinct = len(picked)
        picked.sort(key=lambda q: (-int(cnt[q]), float(fit[q])))
        out: list[PoseCandidate] = []
        for q in picked[: cfg.max_candidates]:
            pose = poses[q].copy()
            pose.setflags(write=False)
            out.append(
                PoseCandidate(pose, float(cnt[q]) / hits.n_points, int(cnt[q]), float(fit[q]))
            )
        return out, n_distinct

    def search_points(
        self, points: ArrayLike, *, prior: ArrayLike | None = None
    ) -> GlobalSearchResult:
        """:meth:`search` for end points ``(M, 2)`` already in the robot frame [m]."""
        t0 = time.perf_counter()
        lat = self._lattice(points, prior)
        hits = self._branch_and_bound(lat, t0)
        cands, n_distinct = self.candidates(hits)
        cfg = self.config
        m = hits.n_points
        best = hits.best / m if m else 0.0
        return GlobalSearchResult(
            candidates=tuple(cands),
            complete=hits.complete,
            reason=hits.reason,
            best_score=best,
            threshold=max(cfg.min_score, best - cfg.score_margin),
            n_points=m,
            angular_step=lat.step,
            n_headings=int(lat.headings.size),
            n_positions=hits.n_positions,
            n_nodes=hits.n_nodes,
            n_hits=int(hits.count.size),
            n_distinct=n_distinct,
            seconds=time.perf_counter() - t0,
        )

    def search(
        self,
        scan: LaserScan,
        *,
        laser_pose: ArrayLike | None = None,
        prior: ArrayLike | None = None,
    ) -> GlobalSearchResult:
        """Every distinct robot pose that explains ``scan``, best first.

        Parameters
        ----------
        scan : LaserScan
        laser_pose : array of shape (3,), optional
            The laser's pose on the robot (``base_from_laser``); default the base origin.
        prior : array of shape (3,), optional
            A pose (map frame) to search around, within ``linear_window`` and
            ``angular_window``; default the whole map, all headings.
        """
        return self.search_points(self.scan_points(scan, laser_pose), prior=prior)


def global_search(
    grid: OccupancyGrid | MapFields,
    scan: LaserScan,
    *,
    config: GlobalSearchConfig | None = None,
    laser_pose: ArrayLike | None = None,
    prior: ArrayLike | None = None,
) -> GlobalSearchResult:
    """Every distinct pose of the map that explains ``scan`` (:meth:`GlobalSearch.search`).

    The map's precomputation is shared through its :class:`MapFields`, so calling this once
    per scan costs the search only.
    """
    return GlobalSearch(grid, config).search(scan, laser_pose=laser_pose, prior=prior)
