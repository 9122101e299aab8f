"""Correlative scan matching (Olson 2009) with a two-level branch and bound, then refinement.

The scan is matched against a :class:`LikelihoodTable`: a grid whose cells hold
``exp(-d^2 / (2 sigma^2))``, ``d`` the distance to the nearest occupied cell of a (sub)map.
The score of a pose is the mean table value at the scan's end points (Olson's
"probabilistically motivated" correlation; Cartographer's real-time CSM scores its
probability grid the same way).

Search (Olson 2009, Section III.C "multi-resolution"; Hess et al. 2016, Algorithm 3):

1. Candidate headings ``theta0 + k * dtheta`` over ``+-angular_window``. Each rotated scan is
   discretised to table cells once; translations are whole-cell shifts over
   ``+-linear_window``.
2. The translations are grouped into ``f x f`` blocks. A low-resolution table whose cell holds
   the maximum of the ``f x f`` high-resolution cells it covers gives, per heading and block,
   an upper bound of the score of every candidate in the block.
3. Blocks are expanded best bound first and the exact score of their ``f^2`` candidates
   computed, until the next bound cannot beat the best score found: the result is the exact
   maximum over the whole discrete search window (branch and bound with two levels).

An optional prior multiplies each score by ``exp(-w_t |dt|^2 - w_r |dtheta|^2)`` (Cartographer's
``translation_delta_cost_weight`` / ``rotation_delta_cost_weight``) and the bound by its maximum
over the block, which keeps the bound valid.

Refinement: Levenberg-Marquardt on residuals ``1 - T(x_p)`` with bilinear interpolation of the
table (analytic gradients), plus weak quadratic priors tying the result to the search's pose
(the role of Cartographer's Ceres scan matcher).

Ambiguity: with ``runner_up_exclusion``, the search goes on after the best pose for the best
score *outside* a neighbourhood of it (:attr:`MatchResult.runner_up_score`): a loop closure
whose runner-up scores almost as well is ambiguous (a corridor, a repeated room).

Information: :func:`match_information` is ``J^T J / N`` of the refinement's residuals at a
pose, the 3 x 3 curvature of the match: its small eigenvalues are the directions the scan does
not constrain (:mod:`symloc.slam.degeneracy`).

Tables built with a ``margin`` (zero-likelihood border cells, at least the search window) are
matched without copying them per match.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from symloc._checks import check_positive
from symloc.errors import ConfigurationError

__all__ = [
    "CsmParams",
    "LikelihoodTable",
    "MatchResult",
    "match_information",
    "match_scan",
    "refine_pose",
    "score_pose",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class CsmParams:
    """Search settings.

    Parameters
    ----------
    linear_window : float
        Half-width of the translation search [m].
    angular_window : float
        Half-width of the heading search [rad].
    angular_step : float
        Heading step [rad]; 0 picks Cartographer's ``acos(1 - r^2 / (2 d^2))`` for the table
        resolution ``r`` and the scan's 90th-percentile point range ``d``, at most
        ``step_range``.
    step_range : float
        Largest range [m] used for that step (a 50 m hall would otherwise ask for 0.06-degree
        steps; the refinement that follows the search is continuous).
    coarse_factor : int
        Block edge ``f`` of the low-resolution level, in cells (>= 1).
    translation_weight, rotation_weight : float
        Prior weights [1/m^2], [1/rad^2] (0 disables).
    refine : bool
        Run the bilinear Levenberg-Marquardt refinement after the search.
    refine_iterations : int
    """

    linear_window: float = 0.3
    angular_window: float = math.radians(15.0)
    angular_step: float = 0.0
    step_range: float = 25.0
    coarse_factor: int = 4
    translation_weight: float = 0.0
    rotation_weight: float = 0.0
    refine: bool = True
    refine_iterations: int = 10

    def __post_init__(self) -> None:
        check_positive(self.linear_window, "CsmParams.linear_window", allow_zero=True)
        check_positive(self.angular_window, "CsmParams.angular_window", allow_zero=True)
        check_positive(self.angular_step, "CsmParams.angular_step", allow_zero=True)
        check_positive(self.step_range, "CsmParams.step_range")
        check_positive(self.translation_weight, "CsmParams.translation_weight", allow_zero=True)
        check_positive(self.rotation_weight, "CsmParams.rotation_weight", allow_zero=True)
        if int(self.coarse_factor) != self.coarse_factor or self.coarse_factor < 1:
            raise ConfigurationError(
                f"CsmParams.coarse_factor: expected an integer >= 1, got {self.coarse_factor}"
            )
        if int(self.refine_iterations) != self.refine_iterations or self.refine_iterations < 0:
            raise ConfigurationError(
                "CsmParams.refine_iterations: expected an integer >= 0, got"
                f" {self.refine_iterations}"
            )


class LikelihoodTable:
    """A smoothed likelihood grid for scan matching, axis-aligned in its own frame.

    Parameters
    ----------
    values : array of shape (H, W)
        Likelihood in [0, 1] at cell centres; row = y, column = x.
    resolution : float
        Cell edge [m].
    origin_xy : array of shape (2,)
        Position of the corner of cell (0, 0) in the table's frame [m].
    margin : int
        Border cells (on every side) beyond the mapped content, all far from any occupied
        cell; a search whose window fits in it needs no padding copy.
    """

    def __init__(
        self, values: ArrayLike, resolution: float, origin_xy: ArrayLike, *, margin: int = 0
    ) -> None:
        v = np.asarray(values, dtype=np.float32)
        if v.ndim != 2 or v.size == 0:
            raise ConfigurationError(f"LikelihoodTable.values: expected (H, W), got {v.shape}")
        self.values = v
        self.resolution = check_positive(resolution, "LikelihoodTable.resolution")
        self.origin_xy = np.asarray(origin_xy, dtype=np.float64).reshape(2)
        self.margin = int(margin)
        self._coarse: dict[int, NDArray[np.float32]] = {}

    @property
    def nbytes(self) -> int:
        """Memory held by the table and its cached coarse levels [bytes]."""
        return int(
            self.values.nbytes
            + sum(c.nbytes for c in self._coarse.values() if c is not self.values)
        )

    @classmethod
    def from_occupied(
        cls,
        occupied: ArrayLike,
        resolution: float,
        origin_xy: ArrayLike,
        sigma: float,
        *,
        max_distance: float | None = None,
        margin: int = 0,
    ) -> LikelihoodTable:
        """Build ``exp(-d^2 / (2 sigma^2))`` from an occupied-cell mask ``(H, W)``.

        ``max_distance`` [m] (default ``4 sigma``) bounds the distance transform work;
        ``margin`` cells are added on every side (the table then starts ``margin`` cells
        before ``origin_xy``), plus the few cells the likelihood needs to fall to 0.
        """
        occ = np.asarray(occupied, dtype=bool)
        sig = check_positive(sigma, "sigma")
        res = float(resolution)
        lim = 4.0 * sig if max_distance is None else float(max_distance)
        reach = math.ceil(lim / res)
        pad = int(margin) + reach + 1 if margin > 0 else 0
        origin = np.asarray(origin_xy, dtype=np.float64).reshape(2) - pad * res
        h, w = occ.shape[0] + 2 * pad, occ.shape[1] + 2 * pad
        values = np.zeros((h, w), np.float32)
        rows = np.flatnonzero(occ.any(axis=1))
        if rows.size == 0:
            return cls(values, res, origin, margin=int(margin))
        cols = np.flatnonzero(occ.any(axis=0))
        # only the occupied cells' bounding box plus the likelihood's reach can be non-zero
        r0, r1 = max(rows[0] + pad - reach, 0), min(rows[-1] + pad + reach + 1, h)
        c0, c1 = max(cols[0] + pad - reach, 0), min(cols[-1] + pad + reach + 1, w)
        box = np.zeros((r1 - r0, c1 - c0), dtype=bool)
        sr0, sc0 = r0 - pad, c0 - pad  # box origin in occ's own cells
        o0, o1 = max(sr0, 0), min(sr0 + box.shape[0], occ.shape[0])
        q0, q1 = max(sc0, 0), min(sc0 + box.shape[1], occ.shape[1])
        box[o0 - sr0 : o1 - sr0, q0 - sc0 : q1 - sc0] = occ[o0:o1, q0:q1]
        d2 = _squared_distance(box, reach) * np.float32(res * res)
        val = np.exp(np.float32(-0.5 / (sig * sig)) * d2)
        val[d2 >= np.float32(lim * lim)] = 0.0
        values[r0:r1, c0:c1] = val
        return cls(values, res, origin, margin=int(margin))

    def coarse(self, factor: int) -> NDArray[np.float32]:
        """Table whose cell ``(r, c)`` holds the max over cells ``[r, r+f) x [c, c+f)``."""
        if factor not in self._coarse:
            if factor == 1:
                self._coarse[factor] = self.values
            else:
                # the max of a window ending at the box of non-zero cells: compute there only
                v = self.values
                rows = np.flatnonzero(v.any(axis=1))
                out = np.zeros_like(v)
                if rows.size:
                    cols = np.flatnonzero(v.any(axis=0))
                    r0, r1 = max(rows[0] - factor, 0), rows[-1] + 1
                    c0, c1 = max(cols[0] - factor, 0), cols[-1] + 1
                    out[r0:r1, c0:c1] = ndimage.maximum_filter(
                        v[r0 : r1 + factor, c0 : c1 + factor],
                        size=factor,
                        origin=-(factor // 2),
                        mode="constant",
                        cval=0.0,
                    )[: r1 - r0, : c1 - c0]
                self._coarse[factor] = out
        return self._coarse[factor]

    def interpolate(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Bilinear value ``(N,)`` and gradient ``(N, 2)`` [1/m] at points ``(N, 2)``."""
        res = self.resolution
        u = (points - self.origin_xy) / res - 0.5
        i0 = np.floor(u).astype(np.intp)
        f = u - i0
        h, w = self.values.shape
        c0 = np.clip(i0[:, 0], 0, w - 1)
        c1 = np.clip(i0[:, 0] + 1, 0, w - 1)
        r0 = np.clip(i0[:, 1], 0, h - 1)
        r1 = np.clip(i0[:, 1] + 1, 0, h - 1)
        v = self.values
        v00 = v[r0, c0].astype(np.float64)
        v01 = v[r0, c1].astype(np.float64)
        v10 = v[r1, c0].astype(np.float64)
        v11 = v[r1, c1].astype(np.float64)
        fx, fy = f[:, 0], f[:, 1]
        val = v00 * (1 - fx) * (1 - fy) + v01 * fx * (1 - fy) + v10 * (1 - fx) * fy + v11 * fx * fy
        gx = ((v01 - v00) * (1 - fy) + (v11 - v10) * fy) / res
        gy = ((v10 - v00) * (1 - fx) + (v11 - v01) * fx) / res
        outside = (u[:, 0] < -1) | (u[:, 1] < -1) | (u[:, 0] > w) | (u[:, 1] > h)
        val[outside] = 0.0
        grad = np.column_stack([gx, gy])
        grad[outside] = 0.0
        return val, grad


@dataclass(frozen=True, slots=True)
class MatchResult:
    """Outcome of :func:`match_scan`.

    Attributes
    ----------
    pose : ndarray of shape (3,)
        Best sensor pose in the table's frame (refined if requested).
    score : float
        Mean table value at the points for ``pose`` (0..1).
    search_score : float
        Best score of the discrete search (including the prior factor).
    n_candidates : int
        Poses whose exact score was computed.
    n_total : int
        Poses in the discrete search window.
    runner_up_score : float
        Best search score outside the ``runner_up_exclusion`` neighbourhood of the best pose
        (-1 when not asked for or the window holds nothing else).
    """

    pose: FloatArray
    score: float
    search_score: float
    n_candidates: int
    n_total: int
    runner_up_score: float = -1.0


def _squared_distance(occupied: NDArray[np.bool_], reach: int) -> NDArray[np.float32]:
    """Squared distance [cells^2] to the nearest occupied cell, exact up to ``reach`` cells.

    Two separable passes of shifted minima (Felzenszwalb and Huttenlocher's decomposition of
    the squared Euclidean distance, restricted to offsets of at most ``reach`` cells per axis,
    which holds every distance up to ``reach``); farther cells get a value above ``reach^2``.
    """
    big = np.float32((reach + 1) ** 2 * 2)
    f = np.where(occupied, np.float32(0.0), big)
    g = f.copy()
    for k in range(1, reach + 1):
        kk = np.float32(k * k)
        np.minimum(g[:, k:], f[:, :-k] + kk, out=g[:, k:])
        np.minimum(g[:, :-k], f[:, k:] + kk, out=g[:, :-k])
    out = g.copy()
    for k in range(1, reach + 1):
        kk = np.float32(k * k)
        np.minimum(out[k:, :], g[:-k, :] + kk, out=out[k:, :])
        np.minimum(out[:-k, :], g[k:, :] + kk, out=out[:-k, :])
    return out


#: Table values gathered at once by the coarse level of :func:`match_scan` (headings x points x
#: blocks x blocks): a wide search (60 degrees, 4 m) gathers ~30 million, 120 MB of float32
#: and as much again for its mask, so the headings are scored in groups within this budget.
_GATHER_BUDGET = 1 << 21


def _coarse_scores(
    coarse: NDArray[np.float32],
    cells: NDArray[np.intp],
    inside: NDArray[np.bool_],
    offs: NDArray[np.intp],
    n_pts: int,
) -> FloatArray:
    """Coarse scores ``(K, nb, nb)``: per heading and block, the mean over the ``N`` points of
    the coarse table at the point's cell ``cells (K, N, 2)`` (row, col) shifted by the block
    offsets ``offs (nb,)`` [cells]; points not ``inside (K, N)`` count 0.

    Computed for groups of headings whose gathered values stay within ``_GATHER_BUDGET``
    (each heading's sum runs over the points in the same order, so the result does not
    depend on the grouping).
    """
    k_all, n = inside.shape
    nb = offs.size
    group = max(1, _GATHER_BUDGET // max(n * nb * nb, 1))
    out = np.empty((k_all, nb, nb), dtype=np.float64)
    for k0 in range(0, k_all, group):
        sl = slice(k0, k0 + group)
        rr = cells[sl, :, 0, None, None] + offs[None, None, :, None]
        cc = cells[sl, :, 1, None, None] + offs[None, None, None, :]
        vals = coarse[rr, cc]
        vals[~inside[sl]] = 0.0
        out[sl] = vals.sum(axis=1) / n_pts
    return out


def _rotate(points: FloatArray, theta: FloatArray) -> FloatArray:
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    x = c * points[None, :, 0] - s * points[None, :, 1]
    y = s * points[None, :, 0] + c * points[None, :, 1]
    return np.stack([x, y], axis=-1)


def score_pose(table: LikelihoodTable, points: ArrayLike, pose: ArrayLike) -> float:
    """Mean bilinear table value at ``points`` (N, 2) (sensor frame) seen from ``pose`` (3,)."""
    p = np.asarray(pose, dtype=np.float64)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if pts.shape[0] == 0:
        return 0.0
    world = _rotate(pts, np.array([p[2]]))[0] + p[:2]
    val, _ = table.interpolate(world)
    return float(val.mean())


def match_scan(
    table: LikelihoodTable,
    points: ArrayLike,
    initial_pose: ArrayLike,
    params: CsmParams | None = None,
    *,
    runner_up_exclusion: tuple[float, float] | None = None,
) -> MatchResult:
    """Find the pose of a scan in ``table`` near ``initial_pose``.

    Parameters
    ----------
    table : LikelihoodTable
    points : array of shape (N, 2)
        Scan end points in the sensor frame [m].
    initial_pose : array of shape (3,)
        Guess of the sensor pose in the table's frame.
    params : CsmParams, optional
    runner_up_exclusion : (float, float), optional
        ``(distance [m], angle [rad])``: also find the best search score among the poses
        farther than this from the best one in translation *or* heading.

    Returns
    -------
    MatchResult
    """
    prm = params if params is not None else CsmParams()
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    p0 = np.asarray(initial_pose, dtype=np.float64).reshape(3)
    if pts.shape[0] == 0:
        return MatchResult(p0.copy(), 0.0, 0.0, 0, 0)
    res = table.resolution
    step = prm.angular_step
    if step == 0.0:
        d = max(float(np.percentile(np.hypot(pts[:, 0], pts[:, 1]), 90)), 2.0 * res)
        d = min(d, prm.step_range)
        step = math.acos(1.0 - res * res / (2.0 * d * d))
    n_ang = math.floor(prm.angular_window / step) if prm.angular_window > 0 else 0
    dthetas = np.arange(-n_ang, n_ang + 1) * step
    n_lin = math.ceil(prm.linear_window / res)
    f = int(prm.coarse_factor)
    span = 2 * n_lin + 1
    nb = -(-span // f)
    # base cells of every rotated point (K, N, 2) as (row, col), shifted into the padded table
    pad = n_lin + f + 1
    h, w = table.values.shape
    rot = _rotate(pts, p0[2] + dthetas) + p0[:2]
    cells = np.floor((rot - table.origin_xy) / res).astype(np.intp)[..., ::-1]
    n_pts = pts.shape[0]
    if table.margin >= pad:  # the table's own border is the padding: no copy
        inside = (
            (cells[..., 0] >= pad)
            & (cells[..., 0] < h - pad)
            & (cells[..., 1] >= pad)
            & (cells[..., 1] < w - pad)
        )
        fine = table.values
        coarse = table.coarse(f)
    else:
        cells = cells + pad
        inside = (
            (cells[..., 0] >= pad)
            & (cells[..., 0] < h + pad)
            & (cells[..., 1] >= pad)
            & (cells[..., 1] < w + pad)
        )
        fine = np.pad(table.values, pad)
        coarse = np.pad(table.coarse(f), pad)
    cells = np.where(inside[..., None], cells, 0)  # masked below
    offs = -n_lin + np.arange(nb) * f
    # prior factor: best over each block (closest offset to zero), exact per candidate
    tw, rw = prm.translation_weight * res * res, prm.rotation_weight
    ang_prior = np.exp(-rw * dthetas**2)

    def _closest(o: NDArray[np.intp]) -> NDArray[np.intp]:
        return np.asarray(np.clip(0, o, o + f - 1), dtype=np.intp)

    cb = _closest(offs)
    block_prior = np.exp(-tw * (cb[:, None] ** 2 + cb[None, :] ** 2))
    coarse_scores = _coarse_scores(coarse, cells, inside, offs, n_pts)
    bounds = coarse_scores * ang_prior[:, None, None] * block_prior[None, :, :]
    order = np.argsort(bounds, axis=None)[::-1]
    flat_bounds = bounds.ravel()[order]
    within = np.arange(f)

    def _search(
        exclude: tuple[int, int, int, float, float] | None,
    ) -> tuple[float, tuple[int, int, int], int]:
        """Branch and bound; ``exclude = (k, dr, dc, r_cells, angle)`` masks a neighbourhood."""
        best = -1.0
        best_idx = (n_ang, n_lin, n_lin)
        n_eval = 0
        batch = 8
        for start in range(0, order.size, batch):
            if flat_bounds[start] <= best:
                break
            ids = order[start : start + batch]
            ids = ids[flat_bounds[start : start + batch] > best]
            k, bi, bj = np.unravel_index(ids, bounds.shape)
            ro = offs[bi][:, None] + within[None, :]  # (B, f) row offsets (cells)
            co = offs[bj][:, None] + within[None, :]
            # (B, N, f, f)
            r_idx = cells[k, :, 0][:, :, None, None] + ro[:, None, :, None]
            c_idx = cells[k, :, 1][:, :, None, None] + co[:, None, None, :]
            vals = (
                np.where(inside[k][:, :, None, None], fine[r_idx, c_idx], 0.0).sum(axis=1) / n_pts
            )
            in_win = (np.abs(ro) <= n_lin)[:, :, None] & (np.abs(co) <= n_lin)[:, None, :]
            if exclude is not None:
                ek, er, ec, rad, ang = exclude
                near_t = (ro[:, :, None] - er) ** 2 + (co[:, None, :] - ec) ** 2 <= rad * rad
                near_a = np.abs(dthetas[k] - dthetas[ek]) <= ang
                in_win &= ~(near_t & near_a[:, None, None])
            prior = ang_prior[k][:, None, None] * np.exp(
                -tw * (ro[:, :, None] ** 2 + co[:, None, :] ** 2)
            )
            vals = np.where(in_win, vals * prior, -1.0)
            n_eval += int(in_win.sum())
            j = int(np.argmax(vals))
            b, a1, a2 = np.unravel_index(j, vals.shape)
            if vals[b, a1, a2] > best:
                best = float(vals[b, a1, a2])
                best_idx = (int(k[b]), int(ro[b, a1]), int(co[b, a2]))
        return best, best_idx, n_eval

    best, best_idx, n_eval = _search(None)
    runner_up = -1.0
    if runner_up_exclusion is not None:
        rad = float(runner_up_exclusion[0]) / res
        runner_up, _, n2 = _search((*best_idx, rad, float(runner_up_exclusion[1])))
        n_eval += n2
    kk, dr, dc = best_idx
    pose = np.array([p0[0] + dc * res, p0[1] + dr * res, p0[2] + dthetas[kk]])
    if prm.refine and prm.refine_iterations > 0:
        pose = refine_pose(table, pts, pose, iterations=prm.refine_iterations)
    pose[2] = math.remainder(pose[2], 2.0 * math.pi)
    score = score_pose(table, pts, pose)
    return MatchResult(
        pose, score, max(best, 0.0), n_eval, int(dthetas.size * span * span), runner_up
    )


def refine_pose(
    table: LikelihoodTable,
    points: ArrayLike,
    pose: ArrayLike,
    *,
    iterations: int = 10,
    translation_weight: float = 1.0,
    rotation_weight: float = 1.0,
) -> FloatArray:
    """Levenberg-Marquardt refinement of ``pose`` (3,) on the bilinear table.

    Minimises ``sum_p (1 - T(x_p))^2 / N + w_t |t - t0|^2 + w_r (theta - theta0)^2`` with
    ``t0, theta0`` the starting pose (weights in 1/m^2 and 1/rad^2, small so they only keep the
    problem well posed). Returns the refined pose ``(3,)``.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    p0 = np.asarray(pose, dtype=np.float64).reshape(3).copy()
    n = max(pts.shape[0], 1)
    wt = math.sqrt(translation_weight * n)
    wr = math.sqrt(rotation_weight * n)

    def _cost(p: FloatArray) -> tuple[float, FloatArray, FloatArray]:
        c, s = math.cos(p[2]), math.sin(p[2])
        rx = c * pts[:, 0] - s * pts[:, 1]
        ry = s * pts[:, 0] + c * pts[:, 1]
        val, grad = table.interpolate(np.column_stack([rx + p[0], ry + p[1]]))
        r = np.concatenate([1.0 - val, wt * (p[:2] - p0[:2]), [wr * (p[2] - p0[2])]])
        jac = np.zeros((pts.shape[0] + 3, 3))
        jac[: pts.shape[0], 0] = -grad[:, 0]
        jac[: pts.shape[0], 1] = -grad[:, 1]
        jac[: pts.shape[0], 2] = -(grad[:, 0] * -ry + grad[:, 1] * rx)
        jac[pts.shape[0], 0] = wt
        jac[pts.shape[0] + 1, 1] = wt
        jac[pts.shape[0] + 2, 2] = wr
        return float(r @ r), r, jac

    p = p0.copy()
    cost, r, jac = _cost(p)
    lam = 1e-3
    for _ in range(int(iterations)):
        jtj = jac.T @ jac
        g = jac.T @ r
        step = np.linalg.solve(jtj + lam * np.diag(np.diag(jtj) + 1e-9), -g)
        cand = p + step
        c_cost, c_r, c_jac = _cost(cand)
        if c_cost < cost:
            p, cost, r, jac = cand, c_cost, c_r, c_jac
            lam = max(lam / 10.0, 1e-7)
            if np.abs(step).max() < 1e-6:
                break
        else:
            lam *= 10.0
            if lam > 1e6:
                break
    return p


def match_information(table: LikelihoodTable, points: ArrayLike, pose: ArrayLike) -> FloatArray:
    """``(3, 3)`` curvature ``J^T J / N`` of the match residuals ``1 - T(x_p)`` at ``pose``.

    ``J`` holds, per point, the gradient of the table value with respect to ``(x, y, theta)``
    [1/m, 1/m, 1/rad]; the matrix is the Gauss-Newton information of the match per point.
    Its eigenvectors with small eigenvalues are the directions the scan does not constrain
    (the axis of a corridor; every direction in an open hall).
    """
    p = np.asarray(pose, dtype=np.float64).reshape(3)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if pts.shape[0] == 0:
        return np.zeros((3, 3))
    c, s = math.cos(p[2]), math.sin(p[2])
    rx = c * pts[:, 0] - s * pts[:, 1]
    ry = s * pts[:, 0] + c * pts[:, 1]
    _, grad = table.interpolate(np.column_stack([rx + p[0], ry + p[1]]))
    jac = np.column_stack([grad[:, 0], grad[:, 1], grad[:, 0] * -ry + grad[:, 1] * rx])
    return np.asarray(jac.T @ jac / pts.shape[0], dtype=np.float64)
