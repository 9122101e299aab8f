"""The paper's Algorithm 1, "Judgement Method of Square Symmetrical Environment", as written.

Steps (Section 4.2): points from the scan (eq. 1-2); the geometric centroid (eq. 3-4, the mean
of the points; ``centroid="area"`` swaps in the area centroid for comparison); the distances
R' of every point to it (eq. 5); sort; count the maximum and minimum values; if there are not
``n`` of each (4 for the paper's square), not symmetric; the distances between adjacent
maximum points must be equal; lines through adjacent maximum points must explain every other
point within epsilon; if so, symmetric and the G-V distance is saved.

"Equal" is not float equality. A distance counts as maximal when it is within its tolerance
of the largest: ``k_sigma * sigma(r) + model_tolerance`` from the range noise, plus
``r * angle_increment``, the spacing of the beams at that range, because the beam nearest a
vertex misses it by up to that much (the paper's Figure 7). "The number of maximum values" is
the number of separate groups of such points along the contour (one group per vertex). When
every point is both maximal and minimal (all distances equal) the room is round (the paper's
"num_max = num_min = N").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.features.centroid import CENTROID_METHODS, area_centroid, mean_centroid
from symloc.scan import LaserScan
from symloc.symmetry.config import SymmetryConfig

__all__ = ["Algorithm1Result", "algorithm1", "count_groups"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Algorithm1Result:
    """Outcome of Algorithm 1.

    Attributes
    ----------
    symmetric : bool
        Step 16 reached ("Environment is square symmetrical").
    kind : str
        ``"polygon"`` (n vertices found and verified), ``"circle"`` (all distances equal),
        ``"not symmetric"`` or ``"unknown"`` (too few points).
    step : int
        The step of Algorithm 1 that decided (7, 11, 16 or 19; 2 for a circle; 0 for unknown).
    num_max, num_min : int
        Step 5's counts (groups of maximal / minimal distances along the contour).
    vertices : ndarray of shape (K, 2)
        The maximum points (one per group), sensor frame [m].
    adjacent_distances : ndarray of shape (K,)
        Step 9's d_12, d_23, ... [m].
    residual : float
        Step 14's largest point-to-line distance [m] (NaN if not reached).
    gv_distance : float
        Step 17's G-V distance [m] (NaN unless symmetric).
    centroid : ndarray of shape (2,)
        Step 2's centroid [m].
    reason : str
        Which test decided.
    """

    symmetric: bool
    kind: str
    step: int
    num_max: int
    num_min: int
    vertices: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    adjacent_distances: FloatArray = field(default_factory=lambda: np.zeros(0))
    residual: float = math.nan
    gv_distance: float = math.nan
    centroid: FloatArray = field(default_factory=lambda: np.full(2, np.nan))
    reason: str = ""


def count_groups(mask: NDArray[np.bool_]) -> tuple[int, NDArray[np.intp]]:
    """Number of separate runs of True in a circular boolean sequence, and each element's run
    label (-1 where False). A sequence that is all True is one run."""
    m = mask.size
    labels = np.full(m, -1, dtype=np.intp)
    if m == 0 or not mask.any():
        return 0, labels
    if mask.all():
        labels[:] = 0
        return 1, labels
    # rotate so the sequence starts just after a False
    shift = int(np.flatnonzero(~mask)[-1]) + 1
    rolled = np.roll(mask, -shift)
    starts = rolled & ~np.concatenate([[False], rolled[:-1]])
    run_id = np.cumsum(starts) - 1
    lab = np.where(rolled, run_id, -1)
    labels = np.roll(lab, shift)
    return int(starts.sum()), labels


def _alternating_extrema(
    rp: FloatArray,
    lab_max: NDArray[np.intp],
    n_max: int,
    lab_min: NDArray[np.intp],
    n_min: int,
) -> tuple[int, int, NDArray[np.intp]]:
    """Count maxima and minima along the contour, where they alternate.

    Around a polygon the distance to the centre rises to a vertex and falls to the middle of
    the next edge, so maxima and minima alternate. Near a minimum the distance is flat and
    the noise makes the "minimal" points come and go; groups of the same kind with no group of
    the other kind between them are one extremum. Returns the counts and, per maximum, the
    index of its largest distance (sorted).
    """
    pos, kind, best = [], [], []
    for lab, n_grp, sign in ((lab_max, n_max, 1.0), (lab_min, n_min, -1.0)):
        for g in range(n_grp):
            members = np.flatnonzero(lab == g)
            k = int(members[np.argmax(sign * rp[members])])
            pos.append(k)
            kind.append(sign > 0)
            best.append(k)
    if not pos:
        return 0, 0, np.zeros(0, dtype=np.intp)
    order = np.argsort(pos)
    kinds = np.asarray(kind)[order]
    idx = np.asarray(best)[order]
    # runs of equal kind, circularly
    start = kinds != np.roll(kinds, 1)
    if not start.any():  # only one kind of extremum
        return (1, 0, idx[:1]) if kinds[0] else (0, 1, np.zeros(0, dtype=np.intp))
    first = int(np.flatnonzero(start)[0])
    kinds = np.roll(kinds, -first)
    idx = np.roll(idx, -first)
    run = np.cumsum(kinds != np.roll(kinds, 1)) - 1
    n_runs = int(run[-1]) + 1
    vert = []
    for r in range(n_runs):
        sel = run == r
        if kinds[sel][0]:
            cand = idx[sel]
            vert.append(int(cand[np.argmax(rp[cand])]))
    num_max = len(vert)
    return num_max, n_runs - num_max, np.sort(np.asarray(vert, dtype=np.intp))


def algorithm1(
    scan: LaserScan,
    *,
    n: int = 4,
    config: SymmetryConfig | None = None,
    centroid: str = "mean",
) -> Algorithm1Result:
    """Run the paper's Algorithm 1 (generalised from 4 to ``n`` vertices) on one scan.

    Parameters
    ----------
    scan : LaserScan
        A 360-degree scan, sensor frame.
    n : int
        Number of vertices of the regular polygon to test (4 in the paper), >= 3.
    config : SymmetryConfig, optional
        Noise model the tolerances derive from.
    centroid : {"mean", "area"}
        Step 2's centroid: the paper's mean of points (default) or the area centroid.

    Returns
    -------
    Algorithm1Result
        Too few points give ``kind == "unknown"``, never an exception.

    Raises
    ------
    ConfigurationError
        For ``n < 3`` or an unknown centroid method.
    """
    cfg = SymmetryConfig() if config is None else config
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
        raise ConfigurationError(f"n: expected an integer >= 3, got {n!r}")
    if centroid not in CENTROID_METHODS:
        raise ConfigurationError(f"centroid: expected one of {CENTROID_METHODS}, got {centroid!r}")
    # step 1
    sp = scan.to_points()
    p = sp.points
    m = p.shape[0]
    if m < max(cfg.min_points, 2 * n):
        return Algorithm1Result(
            False, "unknown", 0, 0, 0, reason=f"too few points ({m}) for {n} vertices"
        )
    # step 2-3
    c = area_centroid(p)[0] if centroid == "area" else mean_centroid(p)
    rp = np.hypot(p[:, 0] - c[0], p[:, 1] - c[1])
    tol = cfg.point_tolerance(sp.ranges) + sp.ranges * scan.angle_increment
    # step 4-5 (the sort of step 4 only serves to find the extremes)
    r_max, r_min = float(rp.max()), float(rp.min())
    is_max = rp >= r_max - tol
    is_min = rp <= r_min + tol
    if is_max.all() and is_min.all():
        return Algorithm1Result(
            True,
            "circle",
            2,
            m,
            m,
            gv_distance=float(rp.mean()),
            centroid=c,
            residual=float(rp.max() - rp.min()),
            reason="every distance to the centroid is both maximal and minimal: a round room",
        )
    n_grp_max, lab_max = count_groups(is_max)
    n_grp_min, lab_min = count_groups(is_min)
    num_max, num_min, vidx = _alternating_extrema(rp, lab_max, n_grp_max, lab_min, n_grp_min)
    # step 6-8
    if num_max != n or num_min != n:
        return Algorithm1Result(
            False,
            "not symmetric",
            7,
            num_max,
            num_min,
            centroid=c,
            reason=f"num_max={num_max}, num_min={num_min}, expected {n} each",
        )
    # step 9: one vertex per maximum (its largest distance), in scan order
    v = p[vidx]
    d = np.hypot(*(np.roll(v, -1, axis=0) - v).T)
    tol_v = tol[vidx]
    tol_d = tol_v + np.roll(tol_v, -1)
    # step 10-12
    if np.any(np.abs(d - d.mean()) > tol_d):
        return Algorithm1Result(
            False,
            "not symmetric",
            11,
            num_max,
            num_min,
            v,
            d,
            centroid=c,
            reason=f"adjacent vertex distances {np.round(d, 3).tolist()} are not equal",
        )
    # step 13-14: each point against the line through the two vertices around it
    seg = np.searchsorted(vidx, np.arange(m), side="right") - 1  # -1 -> wraps to last
    a = v[seg % n]
    b = v[(seg + 1) % n]
    e = b - a
    length = np.maximum(np.hypot(e[:, 0], e[:, 1]), 1e-12)
    dist = np.abs(e[:, 0] * (p[:, 1] - a[:, 1]) - e[:, 1] * (p[:, 0] - a[:, 0])) / length
    residual = float(dist.max())
    # step 15-20
    if np.any(dist > tol):
        return Algorithm1Result(
            False,
            "not symmetric",
            19,
            num_max,
            num_min,
            v,
            d,
            residual,
            centroid=c,
            reason=f"a point lies {residual:.3f} m from the line between its vertices",
        )
    return Algorithm1Result(
        True,
        "polygon",
        16,
        num_max,
        num_min,
        v,
        d,
        residual,
        float(rp[vidx].mean()),
        c,
        reason=f"{n} equal maxima and minima, equal sides, all points on the {n} lines",
    )
