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
and only the residual checks touch the points. The segmentation (steps 1-3, the refinement of
the cuts and the absorption of short pieces) is a chain of integer decisions taken by one
compiled kernel (:func:`symloc.features.split_kernels.segment`); the lines' parameters are
then fitted here, in NumPy, from the pieces it returns.

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
from symloc.features.split_kernels import segment

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


def _closed_start(
    p: FloatArray, tol: FloatArray, *, closed: bool
) -> tuple[FloatArray, FloatArray, int, int | None]:
    """Where the split starts on a closed contour: the points and tolerances rolled to start
    at the point farthest from the sensor (from inside a convex room, next to a corner, so the
    contour's ends rarely need joining), the roll, and the first cut, at the point farthest
    from it. An open run (or fewer than 4 points) is returned as it is, with no first cut."""
    if not closed or p.shape[0] < 4:
        return p, tol, 0, None
    roll = int((p[:, 0] * p[:, 0] + p[:, 1] * p[:, 1]).argmax())
    p = _rolled(p, roll)
    tol = _rolled(tol, roll)
    d0 = p - p[0]
    return p, tol, roll, int((d0[:, 0] ** 2 + d0[:, 1] ** 2).argmax())


def _line_set(
    p: FloatArray,
    tol: FloatArray,
    st: IntArray,
    sp: IntArray,
    *,
    roll: int,
    closed: bool,
    mom: _Moments,
) -> LineSet:
    """The lines of the pieces ``[st, sp)`` of the (rolled) points: TLS fits oriented from each
    line's first point to its last, residuals and projected end points."""
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
        roll=roll,
        closed=closed,
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

    p, tol, roll, first_cut = _closed_start(p, tol, closed=closed)
    # the segmentation (split, boundary refinement, merge, absorption of short pieces) is
    # integer decisions: one compiled kernel takes them, rolling its copy of the points
    pts = np.empty((3, m))
    pts[0] = p[:, 0]
    pts[1] = p[:, 1]
    pts[2] = tol
    pieces, shift = segment(
        pts, -1 if first_cut is None else first_cut, closed, max(2 * min_points, 32)
    )
    st, sp = pieces[0], pieces[1]
    roll = (roll + shift) % m
    p = _rolled(p, shift)
    tol = _rolled(tol, shift)
    mom = _Moments(p)
    return _line_set(p, tol, st, sp, roll=int(roll), closed=bool(closed), mom=mom)
