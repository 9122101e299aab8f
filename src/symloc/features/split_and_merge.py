"""Split-and-merge line extraction with total-least-squares fits, and gap handling.

The reference line extractor of the paper (Section 4.1, [36]; Nguyen et al., "A comparison of
line extraction algorithms using 2D laser rangefinder", IROS 2005):

1. **Split**: a run of points in scan order is cut recursively at the point farthest from the
   chord between its end points, as long as that point is farther than its tolerance.
2. **Fit**: each piece gets a total-least-squares (orthogonal) line fit. The point at a cut
   is given to whichever neighbouring line it lies closer to, so a sparse far corner does not
   bend the next wall's fit.
3. **Merge**: neighbouring pieces are joined while the joined fit still explains every point
   within its tolerance (over-splits caused by noise disappear here).

Fits come from prefix sums of the point moments, so a fit of any contiguous range costs O(1)
and only the residual checks touch the points.

Gaps: :func:`contour_runs` cuts a scan into runs of consecutive points where the laser saw a
continuous surface. A run ends where more than ``max_dropout_beams`` consecutive beams gave no
point (a door, the end of a hallway beyond range, or a long dropout); a few missing beams are a
sensor dropout and the run continues across them.

Tolerances are per point [m]: the caller derives them from the sensor's range noise (see
:class:`symloc.symmetry.SymmetryConfig`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError
from symloc.features.split_kernels import split_cuts

__all__ = ["LineSet", "contour_gaps", "contour_runs", "fit_line_tls", "split_and_merge"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
_Num = FloatArray | np.float64


@dataclass(frozen=True, slots=True)
class LineSet:
    """Lines fitted to consecutive ranges of a point sequence.

    The ranges refer to the sequence rolled by ``roll``: line ``l`` holds the points
    ``np.roll(points, -roll, axis=0)[starts[l]:stops[l]]``. Lines are in sequence order.

    Attributes
    ----------
    starts, stops : ndarray of shape (L,)
        Half-open index range of each line's points in the rolled sequence.
    roll : int
        Rotation applied to a closed contour so that no line wraps around its end (0 when open).
    closed : bool
        Whether the sequence is a closed contour (the last line is adjacent to the first).
    normals : ndarray of shape (L, 2)
        Unit normal of each line; the line is ``normal @ p == offset``.
    offsets : ndarray of shape (L,)
        Signed distance [m] of the line from the origin along its normal.
    centers : ndarray of shape (L, 2)
        Mean of the line's points [m].
    directions : ndarray of shape (L, 2)
        Unit direction, pointing from the line's first point toward its last.
    n_points : ndarray of shape (L,)
        Number of points of each line.
    spread : ndarray of shape (L,)
        Standard deviation [m] of the points' positions along the line.
    rms : ndarray of shape (L,)
        Root-mean-square orthogonal residual [m].
    max_excess : ndarray of shape (L,)
        Largest ratio ``|residual| / tolerance`` over the line's points (<= 1 when every point
        is within tolerance).
    endpoints : ndarray of shape (L, 2, 2)
        First and last point of each line projected onto it [m].
    """

    starts: IntArray
    stops: IntArray
    roll: int
    closed: bool
    normals: FloatArray
    offsets: FloatArray
    centers: FloatArray
    directions: FloatArray
    n_points: IntArray
    spread: FloatArray
    rms: FloatArray
    max_excess: FloatArray
    endpoints: FloatArray

    def __len__(self) -> int:
        return int(self.starts.size)

    @property
    def lengths(self) -> FloatArray:
        """Length [m] of each line between its projected end points, shape (L,)."""
        return np.asarray(
            np.linalg.norm(self.endpoints[:, 1] - self.endpoints[:, 0], axis=-1), dtype=np.float64
        )


def _tls_from_moments(
    n: _Num, sx: _Num, sy: _Num, sxx: _Num, syy: _Num, sxy: _Num
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """TLS lines from summed moments; returns centres, directions, normals, offsets, spread^2."""
    n = np.maximum(n, 1.0)
    mx, my = sx / n, sy / n
    cxx = sxx / n - mx * mx
    cyy = syy / n - my * my
    cxy = sxy / n - mx * my
    theta = 0.5 * np.arctan2(2.0 * cxy, cxx - cyy)
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    shape = (*np.shape(theta), 2)
    d = np.empty(shape)
    d[..., 0] = cos_t
    d[..., 1] = sin_t
    nrm = np.empty(shape)
    nrm[..., 0] = -sin_t
    nrm[..., 1] = cos_t
    c = np.empty(shape)
    c[..., 0] = mx
    c[..., 1] = my
    off = -sin_t * mx + cos_t * my
    # variance along the major axis (the larger eigenvalue)
    half_tr = 0.5 * (cxx + cyy)
    disc = np.sqrt(np.maximum(0.25 * (cxx - cyy) ** 2 + cxy * cxy, 0.0))
    return c, d, nrm, off, np.maximum(half_tr + disc, 0.0)


# rows of the means whose products are subtracted from the second moments: mx mx, my my, mx my
_MEAN_A = np.array([0, 1, 0])
_MEAN_B = np.array([0, 1, 1])


def _normals_offsets(s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """TLS normals (x, y components) and offsets from summed moments ``s`` (6, K).

    The same arithmetic as :func:`_tls_from_moments`, without the centres, directions and
    spread that the split and merge tests do not need.
    """
    q = s[1:] / np.maximum(s[0], 1.0)  # means of x, y, xx, yy, xy
    mx, my = q[0], q[1]
    cxx, cyy, cxy = q[2:] - q[_MEAN_A] * q[_MEAN_B]
    theta = 0.5 * np.arctan2(2.0 * cxy, cxx - cyy)
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    return -sin_t, cos_t, -sin_t * mx + cos_t * my


def fit_line_tls(points: ArrayLike) -> tuple[FloatArray, float, FloatArray, float]:
    """Total-least-squares (orthogonal) line through points.

    Parameters
    ----------
    points : array of shape (M, 2), M >= 2
        x, y [m].

    Returns
    -------
    normal : ndarray of shape (2,)
        Unit normal; the line is ``normal @ p == offset``.
    offset : float
        [m].
    center : ndarray of shape (2,)
        Mean of the points [m].
    rms : float
        Root-mean-square orthogonal residual [m].

    Raises
    ------
    ConfigurationError
        If fewer than 2 points are given.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if p.shape[0] < 2:
        raise ConfigurationError(f"points: expected at least 2 points for a line, got {p.shape[0]}")
    x, y = p[:, 0], p[:, 1]
    m = np.float64(p.shape[0])
    c, _d, nrm, off, _s = _tls_from_moments(
        m, x.sum(), y.sum(), (x * x).sum(), (y * y).sum(), (x * y).sum()
    )
    res = p @ nrm - off
    return nrm, float(off), c, float(np.sqrt(np.mean(res * res)))


def contour_gaps(
    indices: ArrayLike,
    n_beams: int,
    *,
    max_dropout_beams: int,
    no_return: ArrayLike | None = None,
    max_blind_beams: int | None = None,
) -> NDArray[np.bool_]:
    """Which gaps between consecutive valid points open the contour.

    Parameters
    ----------
    indices : array of shape (M,)
        Beam index of each valid point, increasing (``ScanPoints.indices``).
    n_beams : int
        Number of beams in the scan.
    max_dropout_beams : int
        Longest run of missing beams that still counts as a dropout on a continuous wall.
        With ``no_return`` given, only no-return beams count here (a door or a wall beyond
        range gives no return; a sensor dropout gives an invalid reading).
    no_return : array of shape (n_beams,), optional
        True where the beam had no return (``LaserScan.no_return_mask``).
    max_blind_beams : int, optional
        With ``no_return`` given, a gap of more missing beams of any kind than this also opens
        the contour (default: no limit).

    Returns
    -------
    ndarray of shape (M,)
        ``gap[k]`` is True when the gap after point k (to point k + 1; for k = M - 1, the
        wrap-around gap to point 0) opens the contour.
    """
    idx = np.asarray(indices, dtype=np.intp)
    m = idx.size
    if m == 0:
        return np.zeros(0, dtype=bool)
    nxt = np.concatenate((idx[1:], idx[:1] + n_beams))
    missing = nxt - idx - 1
    if no_return is None:
        return missing > max_dropout_beams
    nr = np.asarray(no_return, dtype=bool)
    cum = np.concatenate(([0], np.cumsum(np.concatenate((nr, nr)))))
    n_nr = cum[nxt] - cum[idx + 1]
    cut = n_nr > max_dropout_beams
    if max_blind_beams is not None:
        cut |= missing > max_blind_beams
    return cut


def contour_runs(
    indices: ArrayLike,
    n_beams: int,
    *,
    max_dropout_beams: int,
    wrap: bool,
    no_return: ArrayLike | None = None,
    max_blind_beams: int | None = None,
) -> IntArray:
    """Cut a scan's valid points into runs at the gaps that open the contour.

    Parameters
    ----------
    indices, n_beams, max_dropout_beams, no_return, max_blind_beams
        As :func:`contour_gaps`.
    wrap : bool
        Whether the last beam is adjacent to the first (a full 360-degree scan).

    Returns
    -------
    ndarray of shape (R, 2)
        Half-open ``[start, stop)`` ranges into the points, one per run. When ``wrap`` is true
        and the scan has no gap at all, there is a single run ``[0, M)`` that is a closed
        contour; when the wrap joins the last and the first run, the first run is returned
        with ``stop > M`` meaning it continues from the start (indices modulo M).
    """
    idx = np.asarray(indices, dtype=np.intp)
    m = idx.size
    if m == 0:
        return np.zeros((0, 2), dtype=np.intp)
    gaps = contour_gaps(
        idx,
        n_beams,
        max_dropout_beams=max_dropout_beams,
        no_return=no_return,
        max_blind_beams=max_blind_beams,
    )
    cut = np.flatnonzero(gaps[:-1]) + 1  # a run starts at each cut
    starts = np.concatenate([[0], cut])
    stops = np.concatenate([cut, [m]])
    if wrap and not gaps[-1] and starts.size > 1:
        # the last run continues into the first one
        first_stop = int(stops[0])
        starts = starts[1:].copy()
        stops = stops[1:].copy()
        stops[-1] = m + first_stop
    return np.stack([starts, stops], axis=-1).astype(np.intp)


_A = TypeVar("_A", bound=np.ndarray)


def _rolled(a: _A, k: int) -> _A:
    """``np.roll(a, -k, axis=0)`` without its overhead."""
    k = int(k) % a.shape[0] if a.shape[0] else 0
    return np.concatenate((a[k:], a[:k])) if k else a  # type: ignore[return-value]


class _Moments:
    """Prefix sums of point moments for O(1) fits of contiguous ranges."""

    def __init__(self, p: FloatArray) -> None:
        m = p.shape[0]
        x, y = p[:, 0], p[:, 1]
        cols = np.empty((5, m + 1))
        cols[:, 0] = 0.0
        cols[0, 1:] = x
        cols[1, 1:] = y
        np.multiply(x, x, out=cols[2, 1:])
        np.multiply(y, y, out=cols[3, 1:])
        np.multiply(x, y, out=cols[4, 1:])
        cs = np.empty((6, m + 1))
        cs[0] = np.arange(m + 1)  # the running count (exact, as a running sum of ones is)
        np.cumsum(cols, axis=1, out=cs[1:])
        self.cs = cs
        # contiguous copies of the coordinates: gathering from them is cheaper than from p
        self.px = cols[0, 1:]
        self.py = cols[1, 1:]

    def sums(self, a: ArrayLike, b: ArrayLike) -> FloatArray:
        """Moment sums (6, K) of the ranges [a, b); ``b`` may exceed M (wraps to the start)."""
        a = np.asarray(a)
        b = np.asarray(b)
        cs = self.cs
        m = cs.shape[1] - 1
        over = b > m
        if not over.any():
            return np.asarray(cs[:, b] - cs[:, a], dtype=np.float64)
        s = cs[:, np.minimum(b, m)] - cs[:, a]
        return np.asarray(s + np.where(over, cs[:, np.where(over, b - m, 0)], 0.0), np.float64)

    def fit(self, a: ArrayLike, b: ArrayLike) -> tuple[FloatArray, ...]:
        """TLS fits of the ranges [a, b); ``b`` may exceed M (the range wraps to the start)."""
        s = self.sums(a, b)
        return _tls_from_moments(s[0], s[1], s[2], s[3], s[4], s[5])


def _pair_excess(
    p: FloatArray,
    tol: FloatArray,
    mom: _Moments,
    st: IntArray,
    sp: IntArray,
    *,
    closed: bool,
    which: IntArray | None = None,
) -> FloatArray:
    """For each pair of adjacent pieces (or the pairs ``which``), the largest |residual| / tol
    of their joint TLS fit."""
    m = p.shape[0]
    n_l = st.size
    n_pairs = n_l if closed and n_l > 2 else n_l - 1
    if n_pairs <= 0:
        return np.zeros(0)
    t = np.arange(n_pairs) if which is None else np.asarray(which, dtype=np.intp)
    if t.size == 0:
        return np.zeros(0)
    u = (t + 1) % n_l
    a_all = st[t]
    b_all = np.where(u == 0, sp[u] + m, sp[u])
    out_all = np.full(t.size, np.inf)
    # a joint fit whose RMS residual (the smaller eigenvalue of the scatter) already exceeds
    # the largest tolerance cannot hold every point within its tolerance: skip the point pass
    s = mom.sums(a_all, b_all)
    n = np.maximum(s[0], 1.0)
    cxx = s[3] / n - (s[1] / n) ** 2
    cyy = s[4] / n - (s[2] / n) ** 2
    cxy = s[5] / n - (s[1] / n) * (s[2] / n)
    var_minor = 0.5 * (cxx + cyy) - np.sqrt(0.25 * (cxx - cyy) ** 2 + cxy * cxy)
    cand = (var_minor <= float(np.maximum.reduce(tol)) ** 2).nonzero()[0]
    if cand.size == 0:
        return out_all
    a, b = a_all[cand], b_all[cand]
    nx, ny, off = _normals_offsets(s[:, cand])
    lengths = b - a
    ends = lengths.cumsum()
    first = ends - lengths
    pos = np.arange(int(ends[-1])) - (first - a).repeat(lengths)
    if closed:
        pos %= m
    res = (
        np.abs(
            mom.px[pos] * nx.repeat(lengths)
            + mom.py[pos] * ny.repeat(lengths)
            - off.repeat(lengths)
        )
        / tol[pos]
    )
    out = np.maximum.reduceat(res, first)
    out[lengths <= 2] = 0.0
    out_all[cand] = out
    return out_all


def _reroll(
    p: FloatArray, tol: FloatArray, st: IntArray, sp: IntArray, first: int
) -> tuple[FloatArray, FloatArray, IntArray, IntArray, int]:
    """Roll a closed contour so that piece ``first`` starts at index 0 (pieces stay in order)."""
    m = p.shape[0]
    shift = int(st[first])
    order = _rolled(np.arange(st.size), first)
    st2 = (st[order] - shift) % m
    sp2 = st2 + (sp[order] - st[order])
    return _rolled(p, shift), _rolled(tol, shift), st2, sp2, shift


def _absorbable(
    p: FloatArray,
    tol: FloatArray,
    mom: _Moments,
    st: IntArray,
    sp: IntArray,
    cand: IntArray,
) -> tuple[IntArray, IntArray]:
    """For candidate pieces, whether a prefix fits the previous line and the rest the next one.

    Returns the candidates that can be absorbed and, for each, the number of its points that
    go to the previous line (the smallest such split).
    """
    n_l = st.size
    _c, _d, nrm, off, _s = mom.fit(st, sp)
    prev = (cand - 1) % n_l
    nxt = (cand + 1) % n_l
    lengths = sp[cand] - st[cand]
    first = np.concatenate(([0], np.cumsum(lengths)[:-1]))
    pos = np.arange(int(lengths.sum())) - (first - st[cand]).repeat(lengths)
    qx = mom.px[pos]
    qy = mom.py[pos]
    tq = tol[pos]
    bad_prev = np.abs(
        qx * nrm[prev, 0].repeat(lengths)
        + qy * nrm[prev, 1].repeat(lengths)
        - off[prev].repeat(lengths)
    )
    bad_next = np.abs(
        qx * nrm[nxt, 0].repeat(lengths)
        + qy * nrm[nxt, 1].repeat(lengths)
        - off[nxt].repeat(lengths)
    )
    bp = np.concatenate(([0], np.cumsum(bad_prev > tq)))
    bn = np.concatenate(([0], np.cumsum(bad_next > tq)))
    # split s (0..n) of piece c: points [0, s) to prev, [s, n) to next; with n + 1 choices
    # per piece, laid out as piece-major positions j = first + c_index + s
    n_choice = lengths + 1
    first_c = np.concatenate(([0], np.cumsum(n_choice)[:-1]))
    rep_c = np.arange(cand.size).repeat(n_choice)
    s_c = np.arange(int(n_choice.sum())) - first_c[rep_c]
    g0 = first[rep_c]  # global index of the piece's first point
    pre_bad = bp[g0 + s_c] - bp[g0]
    suf_bad = bn[g0 + lengths[rep_c]] - bn[g0 + s_c]
    ok = (pre_bad == 0) & (suf_bad == 0)
    big = int(s_c.size) + 1
    first_ok = np.minimum.reduceat(np.where(ok, s_c, big), first_c)
    yes = first_ok < big
    return cand[yes], first_ok[yes]


def _absorb_short(
    p: FloatArray,
    tol: FloatArray,
    st: IntArray,
    sp: IntArray,
    *,
    closed: bool,
    max_points: int,
    mom: _Moments | None = None,
) -> tuple[FloatArray, FloatArray, IntArray, IntArray, int]:
    """Hand the points of short pieces to the neighbouring lines when they fit there.

    A piece of at most ``max_points`` points between two lines (typically the few points at a
    sparse far corner) disappears when a prefix of it fits the previous line and the rest the
    next line, each point within its tolerance. Repeats until nothing changes. Returns the
    (possibly re-rolled) points, tolerances, pieces and the extra roll applied.
    """
    total_shift = 0
    m = p.shape[0]
    for _ in range(8):
        n_l = st.size
        if n_l < (3 if closed else 2):
            break
        short = (sp - st <= max_points).nonzero()[0]
        cand = short if closed else short[(short > 0) & (short < n_l - 1)]
        if cand.size == 0:
            break
        if mom is None:
            mom = _Moments(p)
        which, n_prev = _absorbable(p, tol, mom, st, sp, cand)
        if which.size == 0:
            break
        t = int(which[0])
        prev, nxt = (t - 1) % n_l, (t + 1) % n_l
        if closed and t in (0, n_l - 1):
            p, tol, st, sp, shift = _reroll(p, tol, st, sp, prev)
            total_shift = (total_shift + shift) % m
            t, prev, nxt = 1, 0, 2 % n_l
            mom = None  # the points moved
        cut = int(st[t] + n_prev[0])
        sp[prev] = cut
        st[nxt] = cut
        st = np.delete(st, t)
        sp = np.delete(sp, t)
    return p, tol, st, sp, total_shift


def _refine_boundaries(
    p: FloatArray,
    tol: FloatArray,
    st: IntArray,
    sp: IntArray,
    *,
    closed: bool,
    window: int = 8,
    iterations: int = 1,
    mom: _Moments | None = None,
) -> tuple[FloatArray, FloatArray, IntArray, IntArray, int, _Moments]:
    """Move each boundary between two lines to where the points fit them best.

    Within ``window`` points of a boundary, the cut minimises the sum of squared normalised
    residuals of the points before it to the first line and after it to the second; a chord
    split can cut a few points away from the true corner, and those points would otherwise bend
    the next wall's fit. For a closed contour the boundary across the end is refined too, and
    the contour is re-rolled so that the first line starts at index 0. Returns the rolled
    points, tolerances, pieces, the roll applied and the moments of the returned points.
    """
    m = p.shape[0]
    st = st.copy()
    sp = sp.copy()
    total = 0
    n_l = st.size
    if mom is None:
        mom = _Moments(p)
    if n_l < 2:
        return p, tol, st, sp, 0, mom
    offs = np.arange(-window, window)
    for _ in range(iterations):
        nx, ny, off = _normals_offsets(mom.sums(st, sp))
        n_b = n_l if closed else n_l - 1
        t = np.arange(n_b)
        u = (t + 1) % n_l
        b = np.where(u == 0, m, st[u])  # boundary index (m: across the end)
        len_t = sp[t] - st[t]
        len_u = sp[u] - st[u]
        # each boundary moves at most half-way into a neighbour, so no piece empties or two
        # boundaries cross
        lo = -np.minimum(window, np.maximum((len_t - 1) // 2, 0))
        hi = np.minimum(window, np.maximum((len_u - 1) // 2, 0))
        idx = (b[:, None] + offs[None, :]) % m  # (B, 2w)
        q = p[idx]
        tq = tol[idx]
        qx, qy = q[..., 0], q[..., 1]
        e_t = ((qx * nx[t][:, None] + qy * ny[t][:, None] - off[t][:, None]) / tq) ** 2
        e_u = ((qx * nx[u][:, None] + qy * ny[u][:, None] - off[u][:, None]) / tq) ** 2
        valid = (offs[None, :] >= lo[:, None]) & (offs[None, :] < hi[:, None])
        e_t = np.where(valid, e_t, 0.0)
        e_u = np.where(valid, e_u, 0.0)
        # cost of cutting before window position j: sum_{<j} e_t + sum_{>=j} e_u
        cost = np.zeros((n_b, 2 * window + 1))
        e_t.cumsum(axis=1, out=cost[:, 1:])
        cost[:, :-1] += e_u[:, ::-1].cumsum(axis=1)[:, ::-1]
        pos = np.arange(-window, window + 1)
        allowed = (pos[None, :] >= lo[:, None]) & (pos[None, :] <= hi[:, None])
        cost = np.where(allowed, cost, np.inf)
        new_b = b + pos[cost.argmin(axis=1)]
        if np.array_equal(new_b, b):
            break
        if closed:
            cuts = new_b  # cut t separates line t from line t+1; the last one wraps
            st = np.concatenate([[cuts[-1] - m], cuts[:-1]])
            sp = cuts.copy()
            shift = int(st[0])
            if shift:
                st -= shift
                sp -= shift
                p = _rolled(p, shift)
                tol = _rolled(tol, shift)
                total = (total + shift) % m
                mom = _Moments(p)
        else:
            st[1:] = new_b
            sp[:-1] = new_b
    return p, tol, st, sp, total, mom


def split_and_merge(
    points: ArrayLike,
    tolerance: ArrayLike,
    *,
    closed: bool = False,
    min_points: int = 2,
) -> LineSet:
    """Extract lines from points in scan order by split-and-merge with TLS fits.

    Parameters
    ----------
    points : array of shape (M, 2)
        Points of one continuous run [m], in scan order.
    tolerance : float or array of shape (M,)
        Largest orthogonal distance [m] a point may have from its line (> 0); derive it from
        the range noise, e.g. ``k_sigma * sigma(r)``.
    closed : bool
        Treat the sequence as a closed contour (a full scan with no gap): the last point is
        adjacent to the first, and the last line may merge with the first.
    min_points : int
        Pieces with fewer points are kept as their own (short) lines; they are never forced
        into a neighbour they do not fit.

    Returns
    -------
    LineSet

    Raises
    ------
    ConfigurationError
        If the points are not (M, 2) with M >= 2, or a tolerance is not positive.
    """
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 2:
        raise ConfigurationError(f"points: expected shape (M, 2) with M >= 2, got {p.shape}")
    m = p.shape[0]
    tol = np.asarray(tolerance, dtype=np.float64)
    if tol.shape != (m,):
        tol = np.broadcast_to(tol, (m,))
    if not (tol > 0).all():
        raise ConfigurationError("tolerance: expected values > 0 m")
    if min_points < 1:
        raise ConfigurationError(f"min_points: expected >= 1, got {min_points}")

    roll = 0
    first_cut: int | None = None
    if closed and m >= 4:
        # start at the point farthest from the sensor (from inside a convex room, next to a
        # corner, so the contour's ends rarely need joining), and cut first at the point
        # farthest from it
        roll = int((p[:, 0] * p[:, 0] + p[:, 1] * p[:, 1]).argmax())
        p = _rolled(p, roll)
        tol = _rolled(tol, roll)
        d0 = p - p[0]
        first_cut = int((d0[:, 0] ** 2 + d0[:, 1] ** 2).argmax())
    mom = _Moments(p)
    cuts = split_cuts(
        mom.px, mom.py, np.ascontiguousarray(tol), mom.cs, -1 if first_cut is None else first_cut
    )

    # pieces [cuts[t], cuts[t+1]) ; the last piece takes the final point
    bounds = np.asarray(cuts, dtype=np.intp)
    starts = bounds[:-1].copy()
    stops = bounds[1:].copy()
    stops[-1] = m
    p, tol, starts, stops, shift, mom = _refine_boundaries(
        p, tol, starts, stops, closed=closed, mom=mom
    )
    roll = (roll + shift) % m

    # merge: repeatedly join the adjacent pair whose joint fit is best, while it is within tol
    st = np.asarray(starts, dtype=np.intp)
    sp = np.asarray(stops, dtype=np.intp)
    scores = _pair_excess(p, tol, mom, st, sp, closed=closed)
    while scores.size:
        t = int(np.argmin(scores))
        if scores[t] > 1.0:
            break
        u = (t + 1) % st.size
        if u == 0:
            # last line joins the first: re-roll so the joined line starts at index 0
            shift = int(st[t])
            new_first_stop = int(sp[0]) + (m - shift)
            st = np.concatenate([[0], st[1:t] - shift + m])
            sp = np.concatenate([[new_first_stop], sp[1:t] - shift + m])
            p = _rolled(p, shift)
            tol = _rolled(tol, shift)
            roll = (roll + shift) % m
            mom = _Moments(p)
            scores = _pair_excess(p, tol, mom, st, sp, closed=closed)
        else:
            sp[t] = sp[u]
            st = np.concatenate((st[:u], st[u + 1 :]))
            sp = np.concatenate((sp[:u], sp[u + 1 :]))
            # only the pairs that involve the joined piece change
            n_l = st.size
            n_pairs = n_l if closed and n_l > 2 else n_l - 1
            if n_pairs <= 0:
                break
            scores = np.concatenate((scores[:t], scores[t + 1 :]))[:n_pairs]
            if scores.size < n_pairs:
                scores = np.concatenate([scores, np.zeros(n_pairs - scores.size)])
            redo = np.array(
                [r for r in sorted({(t - 1) % n_l, t % n_l}) if r < n_pairs], dtype=np.intp
            )
            scores[redo] = _pair_excess(p, tol, mom, st, sp, closed=closed, which=redo)

    n_before = st.size
    p, tol, st, sp, extra = _absorb_short(
        p, tol, st, sp, closed=closed, max_points=max(2 * min_points, 32), mom=mom
    )
    if st.size != n_before:
        if extra:
            mom = _Moments(p)  # the points were re-rolled (otherwise they, and mom, are the same)
        p, tol, st, sp, shift, mom = _refine_boundaries(p, tol, st, sp, closed=closed, mom=mom)
        roll = (roll + extra + shift) % m
    centers, dirs, normals, offsets, var_along = mom.fit(st, sp)
    # orient each direction from the line's first point toward its last
    first = p[st]
    last = p[sp - 1]
    chord = last - first
    flip = chord[:, 0] * dirs[:, 0] + chord[:, 1] * dirs[:, 1] < 0
    dirs[flip] = -dirs[flip]
    normals = np.empty_like(dirs)
    normals[:, 0] = -dirs[:, 1]
    normals[:, 1] = dirs[:, 0]
    offsets = normals[:, 0] * centers[:, 0] + normals[:, 1] * centers[:, 1]
    # residuals per line (one pass over all points)
    n_pts = (sp - st).astype(np.intp)
    owner = np.arange(st.size).repeat(n_pts)
    res = (
        mom.px * normals[:, 0].repeat(n_pts)
        + mom.py * normals[:, 1].repeat(n_pts)
        - offsets.repeat(n_pts)
    )
    rms = np.sqrt(np.bincount(owner, res * res, minlength=st.size) / np.maximum(n_pts, 1))
    max_excess = np.maximum.reduceat(np.abs(res) / tol, st)
    f_c = first - centers
    l_c = last - centers
    t0 = f_c[:, 0] * dirs[:, 0] + f_c[:, 1] * dirs[:, 1]
    t1 = l_c[:, 0] * dirs[:, 0] + l_c[:, 1] * dirs[:, 1]
    endpoints = np.empty((st.size, 2, 2))
    endpoints[:, 0] = centers + t0[:, None] * dirs
    endpoints[:, 1] = centers + t1[:, None] * dirs
    return LineSet(
        starts=st,
        stops=sp,
        roll=int(roll),
        closed=bool(closed),
        normals=normals,
        offsets=offsets,
        centers=centers,
        directions=dirs,
        n_points=n_pts,
        spread=np.sqrt(var_along),
        rms=rms,
        max_excess=max_excess,
        endpoints=endpoints,
    )
