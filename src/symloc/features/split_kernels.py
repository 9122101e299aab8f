"""Compiled loops of split-and-merge's segmentation (numba, cached on disk).

Split-and-merge's decisions are integers -- where a run of points is cut into lines -- taken
by many small tests (one TLS fit and one residual pass per segment). In NumPy each test is a
few dozen array calls on a few dozen points, so on an 800-point scan the per-call overhead is
most of the cost. The kernels here take the same decisions in one compiled loop:

- :func:`split_cuts`: the recursive split of split-and-merge (before this kernel, ``_split``).
- :func:`segment`: the whole segmentation -- that split, the refinement of the boundaries,
  the merge of adjacent pieces, the absorption of short pieces -- as the NumPy functions
  ``_refine_boundaries``, ``_pair_excess`` and ``_absorb_short`` did it, on the points of
  one run rolled in place as they rolled them. Those NumPy functions are kept, as they were,
  in ``tests/features/split_and_merge_numpy.py``: the tests compare the two.

Each kernel repeats the NumPy expression it replaces operation for operation (the same
moment differences, the same ``0.5 * atan2`` line angle, the same order of products and
sums), so it returns the same integers. The one source of difference is the last bit of
``atan2`` and ``hypot``, which NumPy may take from a SIMD library and the kernel from the C
library: a cut can only move when a residual lies within a rounding error of its tolerance.
The lines' parameters are then computed from the integer cuts by the same NumPy code as
before. ``*_py`` are the plain-Python definitions the kernels are compiled from.

Layout: the points of one run as ``pts (3, M)``, rows x [m], y [m] and tolerance [m]; their
moment prefix sums ``cs (6, M + 1)`` (count, x, y, xx, yy, xy, as ``_Moments.cs``); the pieces
as ``pieces (2, L)``, rows start and stop (half-open point ranges, a stop may exceed M when a
piece wraps), of which the first ``n_l`` columns are in use.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, cast

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["segment", "segment_py", "split_cuts", "split_cuts_py"]


def _jit(fn: Callable[..., Any]) -> Callable[..., Any]:
    return cast(Callable[..., Any], numba.njit(cache=True, nogil=True, error_model="numpy")(fn))


def _sums_py(cs: NDArray[np.float64], a: int, b: int, s: NDArray[np.float64]) -> None:
    """Moment sums ``s (6,)`` of the range ``[a, b)``; ``b`` may exceed M (``_Moments.sums``)."""
    m = cs.shape[1] - 1
    if b > m:
        for r in range(6):
            s[r] = (cs[r, m] - cs[r, a]) + cs[r, b - m]
    else:
        for r in range(6):
            s[r] = cs[r, b] - cs[r, a]


_sums = _jit(_sums_py)


def _line_py(s: NDArray[np.float64]) -> tuple[float, float, float]:
    """TLS normal ``(nx, ny)`` and offset [m] of summed moments ``s (6,)`` (``_normals_offsets``
    and ``_tls_from_moments``)."""
    n = max(s[0], 1.0)
    mx = s[1] / n
    my = s[2] / n
    cxx = s[3] / n - mx * mx
    cyy = s[4] / n - my * my
    cxy = s[5] / n - mx * my
    theta = 0.5 * math.atan2(2.0 * cxy, cxx - cyy)
    cos_t = math.cos(theta)
    sin_t = math.sin(theta)
    return -sin_t, cos_t, -sin_t * mx + cos_t * my


_line = _jit(_line_py)


def _max_excess_py(
    pts: NDArray[np.float64], a: int, b: int, nx: float, ny: float, off: float
) -> float:
    """Largest ``|x nx + y ny - off| / tol`` over the points ``[a, b)`` (indices modulo M);
    NaN as soon as one is NaN (``np.maximum``)."""
    m = pts.shape[1]
    worst = -math.inf
    for k in range(a, b):
        q = k % m
        r = abs(pts[0, q] * nx + pts[1, q] * ny - off) / pts[2, q]
        if r > worst:
            worst = r
        elif r != r:
            return float(r)
    return float(worst)


_max_excess = _jit(_max_excess_py)


def split_cuts_py(
    pts: NDArray[np.float64], cs: NDArray[np.float64], first_cut: int
) -> NDArray[np.int64]:
    """Cut indices of the recursive split, sorted (``_split``'s result as an array).

    A segment ``[i, j]`` (end points included) with at least one interior point is kept whole
    when the TLS line of its interior points ``i + 1 .. j - 1`` holds each of them within its
    tolerance; otherwise it is cut at the first interior point whose distance from the chord
    ``i -> j`` exceeds its tolerance by the largest factor (not cut when none exceeds it).

    Parameters
    ----------
    pts : ndarray of shape (3, M)
        x [m], y [m] and tolerance [m] (> 0) of the points, in contour order.
    cs : ndarray of shape (6, M + 1)
        Their moment prefix sums.
    first_cut : int
        An initial cut (kept only when ``0 < first_cut < M - 1``; -1 for none).

    Returns
    -------
    ndarray of shape (C,), int64
        Sorted cut indices, including 0 and ``M - 1``.
    """
    m = pts.shape[1]
    px = pts[0]
    py = pts[1]
    tol = pts[2]
    s = np.empty(6)
    out = np.empty(m + 2, np.int64)
    stack = np.empty((2 * m + 4, 2), np.int64)
    out[0] = 0
    out[1] = m - 1
    n_out = 2
    top = 0
    if 0 < first_cut < m - 1:
        out[2] = first_cut
        n_out = 3
        stack[0, 0] = 0
        stack[0, 1] = first_cut
        stack[1, 0] = first_cut
        stack[1, 1] = m - 1
        top = 2
    else:
        stack[0, 0] = 0
        stack[0, 1] = m - 1
        top = 1
    while top > 0:
        top -= 1
        i = stack[top, 0]
        j = stack[top, 1]
        if j - i < 2:
            continue
        # the TLS line of the interior points [i + 1, j) holds them all: one wall
        _sums(cs, i + 1, j, s)
        nx, ny, off = _line(s)
        if not _max_excess(pts, i + 1, j, nx, ny, off) > 1.0:
            continue
        # bent: cut at the interior point farthest from the chord (relative to its tolerance)
        ax = px[i]
        ay = py[i]
        dx = px[j] - ax
        dy = py[j] - ay
        length = math.hypot(dx, dy)
        best = -1.0
        arg = -1
        for k in range(i + 1, j):
            qx = px[k] - ax
            qy = py[k] - ay
            dist = abs(dx * qy - dy * qx) / length if length > 1e-12 else math.hypot(qx, qy)
            ratio = dist / tol[k]
            if ratio > best:  # strict: the first point of the largest ratio
                best = ratio
                arg = k
            elif ratio != ratio:
                best = ratio
                break
        if not best > 1.0:
            continue
        out[n_out] = arg
        n_out += 1
        stack[top, 0] = i
        stack[top, 1] = arg
        stack[top + 1, 0] = arg
        stack[top + 1, 1] = j
        top += 2
    return np.sort(out[:n_out])


split_cuts = _jit(split_cuts_py)


def _moments_py(pts: NDArray[np.float64], cs: NDArray[np.float64]) -> None:
    """Fill ``cs (6, M + 1)`` with the moment prefix sums of ``pts`` (sequential, as cumsum)."""
    m = pts.shape[1]
    for r in range(6):
        cs[r, 0] = 0.0
    for k in range(m):
        x = pts[0, k]
        y = pts[1, k]
        cs[0, k + 1] = k + 1
        cs[1, k + 1] = cs[1, k] + x
        cs[2, k + 1] = cs[2, k] + y
        cs[3, k + 1] = cs[3, k] + x * x
        cs[4, k + 1] = cs[4, k] + y * y
        cs[5, k + 1] = cs[5, k] + x * y


_moments = _jit(_moments_py)


def _roll_py(pts: NDArray[np.float64], shift: int, cs: NDArray[np.float64]) -> int:
    """Roll the points in place (``np.roll(pts, -shift, axis=1)``) and rebuild ``cs``; returns
    ``shift`` modulo M."""
    m = pts.shape[1]
    k = shift % m
    if k == 0:
        return 0
    tmp = np.empty(m)
    for r in range(3):
        for i in range(m):
            tmp[i] = pts[r, (i + k) % m]
        for i in range(m):
            pts[r, i] = tmp[i]
    _moments(pts, cs)
    return int(k)


_roll = _jit(_roll_py)


def _pair_score_py(
    pts: NDArray[np.float64],
    cs: NDArray[np.float64],
    pieces: NDArray[np.int64],
    n_l: int,
    t: int,
    tol_max2: float,
    s: NDArray[np.float64],
) -> float:
    """``_pair_excess`` of the pair (t, t + 1): the largest |residual| / tol of their joint fit
    (inf when the fit's minor variance already exceeds the largest tolerance squared, 0 for
    two points or fewer)."""
    m = pts.shape[1]
    u = (t + 1) % n_l
    a = pieces[0, t]
    b = pieces[1, u] + m if u == 0 else pieces[1, u]
    _sums(cs, a, b, s)
    n = max(s[0], 1.0)
    cxx = s[3] / n - (s[1] / n) * (s[1] / n)
    cyy = s[4] / n - (s[2] / n) * (s[2] / n)
    cxy = s[5] / n - (s[1] / n) * (s[2] / n)
    dxy = cxx - cyy
    var_minor = 0.5 * (cxx + cyy) - math.sqrt(0.25 * (dxy * dxy) + cxy * cxy)
    if not var_minor <= tol_max2:
        return math.inf
    if b - a <= 2:
        return 0.0
    nx, ny, off = _line(s)
    return float(_max_excess(pts, a, b, nx, ny, off))


_pair_score = _jit(_pair_score_py)


def _n_pairs_py(n_l: int, closed: bool) -> int:
    """Adjacent pairs of ``n_l`` pieces (the last and the first too on a closed contour)."""
    return n_l if closed and n_l > 2 else n_l - 1


_n_pairs = _jit(_n_pairs_py)


def _refine_py(
    pts: NDArray[np.float64],
    cs: NDArray[np.float64],
    pieces: NDArray[np.int64],
    n_l: int,
    closed: bool,
    window: int,
) -> int:
    """``_refine_boundaries`` (one iteration) in place; returns the roll applied to the points
    (0 <= roll < M)."""
    m = pts.shape[1]
    if n_l < 2:
        return 0
    w = window
    st = pieces[0]
    sp = pieces[1]
    lines = np.empty((n_l, 3))
    s = np.empty(6)
    for t in range(n_l):
        _sums(cs, st[t], sp[t], s)
        nx, ny, off = _line(s)
        lines[t, 0] = nx
        lines[t, 1] = ny
        lines[t, 2] = off
    n_b = n_l if closed else n_l - 1
    new_b = np.empty(n_b, np.int64)
    e_t = np.empty(2 * w)
    suffix = np.empty(2 * w)
    changed = False
    for t in range(n_b):
        u = (t + 1) % n_l
        b = m if u == 0 else st[u]
        lo = -min(w, max((sp[t] - st[t] - 1) // 2, 0))
        hi = min(w, max((sp[u] - st[u] - 1) // 2, 0))
        # squared normalised residuals to line t and to line u in the window around b,
        # the latter summed from the window's end as the reversed cumsum did
        ru = 0.0
        for j in range(2 * w - 1, -1, -1):
            o = j - w
            vt = 0.0
            vu = 0.0
            if o >= lo and o < hi:
                q = (b + o) % m
                vt = (pts[0, q] * lines[t, 0] + pts[1, q] * lines[t, 1] - lines[t, 2]) / pts[2, q]
                vu = (pts[0, q] * lines[u, 0] + pts[1, q] * lines[u, 1] - lines[u, 2]) / pts[2, q]
            e_t[j] = vt * vt
            ru = vu * vu if j == 2 * w - 1 else ru + vu * vu
            suffix[j] = ru
        # cost of cutting before window position j: sum_{<j} e_t + sum_{>=j} e_u; the first
        # smallest among the allowed positions [lo, hi]
        best = math.inf
        arg = 0
        ct = 0.0
        for j in range(2 * w + 1):
            if j == 1:
                ct = e_t[0]
            elif j > 1:
                ct = ct + e_t[j - 1]
            if j == 0:
                c = suffix[0]
            elif j < 2 * w:
                c = ct + suffix[j]
            else:
                c = ct
            if not (lo <= j - w <= hi):
                c = math.inf
            if j == 0 or c < best or (c != c and best == best):  # np.argmin: first NaN wins
                best = c
                arg = j
        new_b[t] = b + (arg - w)
        changed = changed or new_b[t] != b
    if not changed:
        return 0
    if not closed:
        for t in range(n_b):
            st[t + 1] = new_b[t]
            sp[t] = new_b[t]
        return 0
    st[0] = new_b[n_b - 1] - m
    for t in range(1, n_l):
        st[t] = new_b[t - 1]
    for t in range(n_l):
        sp[t] = new_b[t]
    shift = st[0]
    if shift == 0:
        return 0
    for t in range(n_l):
        st[t] -= shift
        sp[t] -= shift
    return int(_roll(pts, shift, cs))


_refine = _jit(_refine_py)


def _absorbable_py(
    pts: NDArray[np.float64],
    cs: NDArray[np.float64],
    pieces: NDArray[np.int64],
    n_l: int,
    c: int,
    s: NDArray[np.float64],
) -> int:
    """``_absorbable`` for piece ``c``: the smallest number of its points that can go to the
    previous line with the rest fitting the next line (each point within its tolerance), or
    -1 when there is none."""
    prev = (c - 1) % n_l
    nxt = (c + 1) % n_l
    _sums(cs, pieces[0, prev], pieces[1, prev], s)
    pnx, pny, poff = _line(s)
    _sums(cs, pieces[0, nxt], pieces[1, nxt], s)
    nnx, nny, noff = _line(s)
    n = pieces[1, c] - pieces[0, c]
    first_bad_prev = n  # points [0, first_bad_prev) all fit the previous line
    last_bad_next = 0  # points [last_bad_next, n) all fit the next line
    for k in range(n):
        q = pieces[0, c] + k
        x = pts[0, q]
        y = pts[1, q]
        if k < first_bad_prev and abs(x * pnx + y * pny - poff) > pts[2, q]:
            first_bad_prev = k
        if abs(x * nnx + y * nny - noff) > pts[2, q]:
            last_bad_next = k + 1
    return last_bad_next if last_bad_next <= first_bad_prev else -1


_absorbable = _jit(_absorbable_py)


def _delete_py(a: NDArray[Any], n: int, i: int) -> None:
    """Remove column ``i`` of the first ``n`` columns of ``a`` (the later ones move down)."""
    for k in range(i, n - 1):
        a[..., k] = a[..., k + 1]


_delete = _jit(_delete_py)


def _merge_py(
    pts: NDArray[np.float64],
    cs: NDArray[np.float64],
    pieces: NDArray[np.int64],
    n_l: int,
    closed: bool,
) -> tuple[int, int]:
    """The merge loop: join the adjacent pair whose joint fit is best while it is within
    tolerance (scores kept and updated as the NumPy loop kept them). Returns the number of
    pieces and the roll applied to the points."""
    m = pts.shape[1]
    total = 0
    s = np.empty(6)
    tol_max = -math.inf
    for k in range(m):
        tol_max = max(tol_max, pts[2, k])
    tol_max2 = tol_max * tol_max
    scores = np.empty(n_l + 1)
    n_sc = max(_n_pairs(n_l, closed), 0)
    for t in range(n_sc):
        scores[t] = _pair_score(pts, cs, pieces, n_l, t, tol_max2, s)
    while n_sc > 0:
        t = 0  # np.argmin: the first smallest score (the first NaN if any)
        for k in range(n_sc):
            if scores[k] != scores[k]:
                t = k
                break
            if scores[k] < scores[t]:
                t = k
        if scores[t] > 1.0:
            break
        u = (t + 1) % n_l
        if u == 0:
            # last line joins the first: re-roll so the joined line starts at index 0
            shift = pieces[0, t]
            new_first_stop = pieces[1, 0] + (m - shift)
            for k in range(1, t):
                pieces[0, k] = pieces[0, k] - shift + m
                pieces[1, k] = pieces[1, k] - shift + m
            pieces[0, 0] = 0
            pieces[1, 0] = new_first_stop
            n_l = t
            total = (total + _roll(pts, shift, cs)) % m
            n_sc = max(_n_pairs(n_l, closed), 0)
            for k in range(n_sc):
                scores[k] = _pair_score(pts, cs, pieces, n_l, k, tol_max2, s)
            continue
        pieces[1, t] = pieces[1, u]
        _delete(pieces, n_l, u)
        n_l -= 1
        # only the pairs that involve the joined piece change
        n_pairs = _n_pairs(n_l, closed)
        if n_pairs <= 0:
            break
        _delete(scores, n_sc, t)
        for k in range(n_sc - 1, n_pairs):
            scores[k] = 0.0
        n_sc = n_pairs
        r1 = (t - 1) % n_l
        r2 = t % n_l
        if r1 < n_pairs:
            scores[r1] = _pair_score(pts, cs, pieces, n_l, r1, tol_max2, s)
        if r2 != r1 and r2 < n_pairs:
            scores[r2] = _pair_score(pts, cs, pieces, n_l, r2, tol_max2, s)
    return n_l, total


_merge = _jit(_merge_py)


def _absorb_py(
    pts: NDArray[np.float64],
    cs: NDArray[np.float64],
    pieces: NDArray[np.int64],
    n_l: int,
    closed: bool,
    max_points: int,
) -> tuple[int, int]:
    """``_absorb_short``: hand the points of short pieces to their neighbours when they fit
    there, up to 8 times. Returns the number of pieces and the roll applied to the points."""
    m = pts.shape[1]
    total = 0
    s = np.empty(6)
    for _ in range(8):
        if n_l < (3 if closed else 2):
            break
        t = -1
        n_prev = 0
        for c in range(n_l):
            if pieces[1, c] - pieces[0, c] > max_points or (
                not closed and (c == 0 or c == n_l - 1)
            ):
                continue
            k = _absorbable(pts, cs, pieces, n_l, c, s)
            if k >= 0:
                t = c
                n_prev = k
                break
        if t < 0:
            break
        prev = (t - 1) % n_l
        nxt = (t + 1) % n_l
        if closed and (t == 0 or t == n_l - 1):
            # roll so that piece prev starts at index 0 (``_reroll``)
            shift = pieces[0, prev]
            old = pieces[:, :n_l].copy()
            for i in range(n_l):
                j = (i + prev) % n_l
                pieces[0, i] = (old[0, j] - shift) % m
                pieces[1, i] = pieces[0, i] + (old[1, j] - old[0, j])
            total = (total + _roll(pts, shift, cs)) % m
            t = 1
            prev = 0
            nxt = 2 % n_l
        cut = pieces[0, t] + n_prev
        pieces[1, prev] = cut
        pieces[0, nxt] = cut
        _delete(pieces, n_l, t)
        n_l -= 1
    return n_l, total


_absorb = _jit(_absorb_py)


def segment_py(
    pts: NDArray[np.float64], first_cut: int, closed: bool, max_points: int
) -> tuple[NDArray[np.int64], int]:
    """Split-and-merge's segmentation: split, refine, merge, absorb short pieces, refine.

    The integer part of :func:`symloc.features.split_and_merge.split_and_merge` after its
    initial roll, step for step as its NumPy code did it (``_split``, ``_refine_boundaries``,
    the merge loop over ``_pair_excess``, ``_absorb_short``).

    Parameters
    ----------
    pts : ndarray of shape (3, M)
        x [m], y [m] and tolerance [m] (> 0) of the points in contour order; **rolled in
        place** as the segmentation rolls a closed contour.
    first_cut : int
        The split's first cut (-1: none).
    closed : bool
        A closed contour (the last point next to the first).
    max_points : int
        Pieces of at most this many points are absorbed by their neighbours when they fit.

    Returns
    -------
    pieces : ndarray of shape (2, L), int64
        Starts and stops (half-open point ranges) of the lines, in the rolled points.
    shift : int
        The roll applied to the points, ``0 <= shift < M`` (``np.roll(a, -shift)``).
    """
    m = pts.shape[1]
    cs = np.empty((6, m + 1))
    _moments(pts, cs)
    cuts = split_cuts(pts, cs, first_cut)
    n_l = cuts.shape[0] - 1
    pieces = np.empty((2, n_l), np.int64)
    pieces[0] = cuts[:-1]
    pieces[1] = cuts[1:]
    pieces[1, n_l - 1] = m
    total = _refine(pts, cs, pieces, n_l, closed, 8)
    n_l, shift = _merge(pts, cs, pieces, n_l, closed)
    total = (total + shift) % m
    n_before = n_l
    n_l, shift = _absorb(pts, cs, pieces, n_l, closed, max_points)
    total = (total + shift) % m
    if n_l != n_before:
        total = (total + _refine(pts, cs, pieces, n_l, closed, 8)) % m
    return pieces[:, :n_l].copy(), int(total)


segment = _jit(segment_py)
