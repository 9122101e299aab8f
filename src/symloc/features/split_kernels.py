"""Compiled loops of split-and-merge's segmentation (numba, cached on disk).

Split-and-merge's decisions are integers -- where a run of points is cut into lines -- taken
by many small tests (one TLS fit and one residual pass per segment). In NumPy each test is a
few dozen array calls on a few dozen points, so on an 800-point scan the per-call overhead is
most of the cost. The kernels here take the same decisions in one compiled loop:

- :func:`split_cuts`: the recursive split of split-and-merge (before this kernel, ``_split``).
- :func:`segment`: the whole segmentation -- that split, the refinement of the boundaries,
  the merge of adjacent pieces, the absorption of short pieces -- as the NumPy functions
  ``_refine_boundaries``, ``_pair_excess`` and ``_absorb_short`` did it, on the points of
  one run rolled in place as they rolled them.

Each kernel repeats the NumPy expression it replaces operation for operation (the same
moment differences, the same ``0.5 * atan2`` line angle, the same order of products and
sums), so it returns the same integers. The one source of difference is the last bit of
``atan2`` and ``hypot``, which NumPy may take from a SIMD library and the kernel from the C
library: a cut can only move when a residual lies within a rounding error of its tolerance.
The lines' parameters are then computed from the integer cuts by the same NumPy code as
before. ``*_py`` are the plain-Python definitions the kernels are compiled from.
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


def split_cuts_py(
    px: NDArray[np.float64],
    py: NDArray[np.float64],
    tol: NDArray[np.float64],
    cs: NDArray[np.float64],
    first_cut: int,
) -> NDArray[np.int64]:
    """Cut indices of the recursive split, sorted (``_split``'s result as an array).

    A segment ``[i, j]`` (end points included) with at least one interior point is kept whole
    when the TLS line of its interior points ``i + 1 .. j - 1`` holds each of them within its
    tolerance; otherwise it is cut at the first interior point whose distance from the chord
    ``i -> j`` exceeds its tolerance by the largest factor (not cut when none exceeds it).

    Parameters
    ----------
    px, py : ndarray of shape (M,)
        Point coordinates [m], in contour order.
    tol : ndarray of shape (M,)
        Tolerance of each point [m], > 0.
    cs : ndarray of shape (6, M + 1)
        Prefix sums of the point count and moments x, y, xx, yy, xy (``_Moments.cs``).
    first_cut : int
        An initial cut (kept only when ``0 < first_cut < M - 1``; -1 for none).

    Returns
    -------
    ndarray of shape (C,), int64
        Sorted cut indices, including 0 and ``M - 1``.
    """
    m = px.shape[0]
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
        # the TLS line of the interior points [i + 1, j) from the moment sums
        n = max(cs[0, j] - cs[0, i + 1], 1.0)
        mx = (cs[1, j] - cs[1, i + 1]) / n
        my = (cs[2, j] - cs[2, i + 1]) / n
        cxx = (cs[3, j] - cs[3, i + 1]) / n - mx * mx
        cyy = (cs[4, j] - cs[4, i + 1]) / n - my * my
        cxy = (cs[5, j] - cs[5, i + 1]) / n - mx * my
        theta = 0.5 * math.atan2(2.0 * cxy, cxx - cyy)
        cos_t = math.cos(theta)
        sin_t = math.sin(theta)
        nx = -sin_t
        ny = cos_t
        off = -sin_t * mx + cos_t * my
        worst = -1.0
        for k in range(i + 1, j):
            r = abs(px[k] * nx + py[k] * ny - off) / tol[k]
            if r > worst:
                worst = r
            elif r != r:  # NaN wins, as in np.maximum
                worst = r
                break
        if not worst > 1.0:
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


def _moments_py(px: NDArray[np.float64], py: NDArray[np.float64], cs: NDArray[np.float64]) -> None:
    """Fill ``cs (6, M + 1)`` with the prefix sums of ``_Moments`` (sequential, as cumsum)."""
    m = px.shape[0]
    for r in range(6):
        cs[r, 0] = 0.0
    for k in range(m):
        x = px[k]
        y = py[k]
        cs[0, k + 1] = k + 1
        cs[1, k + 1] = cs[1, k] + x
        cs[2, k + 1] = cs[2, k] + y
        cs[3, k + 1] = cs[3, k] + x * x
        cs[4, k + 1] = cs[4, k] + y * y
        cs[5, k + 1] = cs[5, k] + x * y


_moments = _jit(_moments_py)


def _roll_py(a: NDArray[np.float64], shift: int, tmp: NDArray[np.float64]) -> None:
    """``a[:] = np.roll(a, -shift)`` in place (``tmp`` of the same length as scratch)."""
    m = a.shape[0]
    k = shift % m
    if k == 0:
        return
    for i in range(m):
        tmp[i] = a[(i + k) % m]
    for i in range(m):
        a[i] = tmp[i]


_roll = _jit(_roll_py)


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
    """TLS normal ``(nx, ny)`` and offset of summed moments ``s (6,)`` (``_normals_offsets``)."""
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


def _pair_score_py(
    px: NDArray[np.float64],
    py: NDArray[np.float64],
    tol: NDArray[np.float64],
    cs: NDArray[np.float64],
    st: NDArray[np.int64],
    sp: NDArray[np.int64],
    n_l: int,
    t: int,
    closed: bool,
    tol_max2: float,
    s: NDArray[np.float64],
) -> float:
    """``_pair_excess`` of the pair (t, t + 1): the largest |residual| / tol of their joint fit
    (inf when the fit's minor variance already exceeds the largest tolerance squared)."""
    m = px.shape[0]
    u = (t + 1) % n_l
    a = st[t]
    b = sp[u] + m if u == 0 else sp[u]
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
    worst = -math.inf
    for k in range(a, b):
        q = k % m if closed else k
        r = abs(px[q] * nx + py[q] * ny - off) / tol[q]
        if r > worst:
            worst = r
        elif r != r:
            return float(r)
    return float(worst)


_pair_score = _jit(_pair_score_py)


def _pair_scores_py(
    px: NDArray[np.float64],
    py: NDArray[np.float64],
    tol: NDArray[np.float64],
    cs: NDArray[np.float64],
    st: NDArray[np.int64],
    sp: NDArray[np.int64],
    n_l: int,
    closed: bool,
    tol_max2: float,
    s: NDArray[np.float64],
    scores: NDArray[np.float64],
) -> int:
    """All pair scores into ``scores``; returns their number (``_pair_excess`` without
    ``which``)."""
    n_pairs = n_l if closed and n_l > 2 else n_l - 1
    n_pairs = max(n_pairs, 0)
    for t in range(n_pairs):
        scores[t] = _pair_score(px, py, tol, cs, st, sp, n_l, t, closed, tol_max2, s)
    return n_pairs


_pair_scores = _jit(_pair_scores_py)


def _refine_py(
    px: NDArray[np.float64],
    py: NDArray[np.float64],
    tol: NDArray[np.float64],
    cs: NDArray[np.float64],
    st: NDArray[np.int64],
    sp: NDArray[np.int64],
    n_l: int,
    closed: bool,
    window: int,
    tmp: NDArray[np.float64],
) -> int:
    """``_refine_boundaries`` (one iteration) in place; returns the roll applied to the points
    (``px``, ``py``, ``tol`` rolled and ``cs`` rebuilt when it is not 0)."""
    m = px.shape[0]
    if n_l < 2:
        return 0
    w = window
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
    e_u = np.empty(2 * w)
    suffix = np.empty(2 * w)
    changed = False
    for t in range(n_b):
        u = (t + 1) % n_l
        b = m if u == 0 else st[u]
        lo = -min(w, max((sp[t] - st[t] - 1) // 2, 0))
        hi = min(w, max((sp[u] - st[u] - 1) // 2, 0))
        for j in range(2 * w):
            o = j - w
            if o >= lo and o < hi:
                q = (b + o) % m
                vt = (px[q] * lines[t, 0] + py[q] * lines[t, 1] - lines[t, 2]) / tol[q]
                vu = (px[q] * lines[u, 0] + py[q] * lines[u, 1] - lines[u, 2]) / tol[q]
                e_t[j] = vt * vt
                e_u[j] = vu * vu
            else:
                e_t[j] = 0.0
                e_u[j] = 0.0
        # cost of cutting before window position j: sum_{<j} e_t + sum_{>=j} e_u, the two
        # running sums in cumsum's order; positions outside [lo, hi] are not allowed
        best = math.inf
        arg = 0
        ct = 0.0
        ru = 0.0
        for j in range(2 * w - 1, -1, -1):
            ru = e_u[j] if j == 2 * w - 1 else ru + e_u[j]
            suffix[j] = ru
        for j in range(2 * w + 1):
            if j > 0:
                ct = e_t[0] if j == 1 else ct + e_t[j - 1]
            c = ct + suffix[j] if j < 2 * w else ct
            if j == 0:
                c = suffix[0]
            o = j - w
            if not (o >= lo and o <= hi):
                c = math.inf
            if j == 0:
                best = c
                arg = 0
            elif c < best:
                best = c
                arg = j
        new_b[t] = b + (arg - w)
        if new_b[t] != b:
            changed = True
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
    _roll(px, shift, tmp)
    _roll(py, shift, tmp)
    _roll(tol, shift, tmp)
    _moments(px, py, cs)
    return int(shift % m)


_refine = _jit(_refine_py)


def _absorbable_py(
    px: NDArray[np.float64],
    py: NDArray[np.float64],
    tol: NDArray[np.float64],
    cs: NDArray[np.float64],
    st: NDArray[np.int64],
    sp: NDArray[np.int64],
    n_l: int,
    c: int,
    s: NDArray[np.float64],
) -> int:
    """``_absorbable`` for piece ``c``: the smallest number of its points that can go to the
    previous line with the rest fitting the next line (each point within its tolerance), or
    -1 when there is none."""
    prev = (c - 1) % n_l
    nxt = (c + 1) % n_l
    _sums(cs, st[prev], sp[prev], s)
    pnx, pny, poff = _line(s)
    _sums(cs, st[nxt], sp[nxt], s)
    nnx, nny, noff = _line(s)
    n = sp[c] - st[c]
    first_bad_prev = n  # points [0, first_bad_prev) all fit the previous line
    last_bad_next = 0  # points [last_bad_next, n) all fit the next line
    for k in range(n):
        q = st[c] + k
        x = px[q]
        y = py[q]
        if k < first_bad_prev and abs(x * pnx + y * pny - poff) > tol[q]:
            first_bad_prev = k
        if abs(x * nnx + y * nny - noff) > tol[q]:
            last_bad_next = k + 1
    return last_bad_next if last_bad_next <= first_bad_prev else -1


_absorbable = _jit(_absorbable_py)


def _reroll_py(
    px: NDArray[np.float64],
    py: NDArray[np.float64],
    tol: NDArray[np.float64],
    st: NDArray[np.int64],
    sp: NDArray[np.int64],
    n_l: int,
    first: int,
    tmp: NDArray[np.float64],
) -> int:
    """``_reroll``: roll the points so that piece ``first`` starts at index 0; returns the
    shift (``cs`` is not rebuilt here)."""
    m = px.shape[0]
    shift = st[first]
    old_st = st[:n_l].copy()
    old_sp = sp[:n_l].copy()
    for i in range(n_l):
        j = (i + first) % n_l
        st[i] = (old_st[j] - shift) % m
        sp[i] = st[i] + (old_sp[j] - old_st[j])
    _roll(px, shift, tmp)
    _roll(py, shift, tmp)
    _roll(tol, shift, tmp)
    return int(shift)


_reroll = _jit(_reroll_py)


def _delete_py(a: NDArray[Any], n: int, i: int) -> None:
    """Remove entry ``i`` of the first ``n`` entries of ``a`` (the later ones move down)."""
    for k in range(i, n - 1):
        a[k] = a[k + 1]


_delete = _jit(_delete_py)


def segment_py(
    px: NDArray[np.float64],
    py: NDArray[np.float64],
    tol: NDArray[np.float64],
    first_cut: int,
    closed: bool,
    max_points: int,
) -> tuple[NDArray[np.int64], NDArray[np.int64], int]:
    """Split-and-merge's segmentation: split, refine, merge, absorb short pieces, refine.

    The integer part of :func:`symloc.features.split_and_merge.split_and_merge` after its
    initial roll, step for step as its NumPy code did it (``_split``, ``_refine_boundaries``,
    the merge loop over ``_pair_excess``, ``_absorb_short``).

    Parameters
    ----------
    px, py : ndarray of shape (M,)
        Point coordinates [m] in contour order; **rolled in place** as the segmentation rolls
        a closed contour.
    tol : ndarray of shape (M,)
        Tolerances [m] (> 0), rolled in place with the points.
    first_cut : int
        The split's first cut (-1: none).
    closed : bool
        A closed contour (the last point next to the first).
    max_points : int
        Pieces of at most this many points are absorbed by their neighbours when they fit.

    Returns
    -------
    starts, stops : ndarray of shape (L,), int64
        Half-open point ranges of the lines, in the rolled points.
    shift : int
        The roll applied to the points, ``0 <= shift < M`` (``np.roll(a, -shift)``).
    """
    m = px.shape[0]
    tmp = np.empty(m)
    s = np.empty(6)
    cs = np.empty((6, m + 1))
    _moments(px, py, cs)
    cuts = split_cuts(px, py, tol, cs, first_cut)
    n_l = cuts.shape[0] - 1
    st = np.empty(n_l, np.int64)
    sp = np.empty(n_l, np.int64)
    for t in range(n_l):
        st[t] = cuts[t]
        sp[t] = cuts[t + 1]
    sp[n_l - 1] = m
    total = _refine(px, py, tol, cs, st, sp, n_l, closed, 8, tmp)

    # merge: repeatedly join the adjacent pair whose joint fit is best, while it is within tol
    tol_max = -math.inf
    for k in range(m):
        tol_max = max(tol_max, tol[k])
    tol_max2 = tol_max * tol_max
    scores = np.empty(n_l + 1)
    n_sc = _pair_scores(px, py, tol, cs, st, sp, n_l, closed, tol_max2, s, scores)
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
            shift = st[t]
            new_first_stop = sp[0] + (m - shift)
            for k in range(1, t):
                st[k] = st[k] - shift + m
                sp[k] = sp[k] - shift + m
            st[0] = 0
            sp[0] = new_first_stop
            n_l = t
            _roll(px, shift, tmp)
            _roll(py, shift, tmp)
            _roll(tol, shift, tmp)
            total = (total + shift) % m
            _moments(px, py, cs)
            n_sc = _pair_scores(px, py, tol, cs, st, sp, n_l, closed, tol_max2, s, scores)
        else:
            sp[t] = sp[u]
            _delete(st, n_l, u)
            _delete(sp, n_l, u)
            n_l -= 1
            # only the pairs that involve the joined piece change
            n_pairs = n_l if closed and n_l > 2 else n_l - 1
            if n_pairs <= 0:
                break
            _delete(scores, n_sc, t)
            for k in range(n_sc - 1, n_pairs):
                scores[k] = 0.0
            n_sc = n_pairs
            r1 = (t - 1) % n_l
            r2 = t % n_l
            if r1 < n_pairs:
                scores[r1] = _pair_score(px, py, tol, cs, st, sp, n_l, r1, closed, tol_max2, s)
            if r2 != r1 and r2 < n_pairs:
                scores[r2] = _pair_score(px, py, tol, cs, st, sp, n_l, r2, closed, tol_max2, s)

    # absorb short pieces into their neighbours, then refine again if any went
    n_before = n_l
    for _ in range(8):
        if n_l < (3 if closed else 2):
            break
        t = -1
        n_prev = 0
        for c in range(n_l):
            if sp[c] - st[c] > max_points or (not closed and (c == 0 or c == n_l - 1)):
                continue
            k = _absorbable(px, py, tol, cs, st, sp, n_l, c, s)
            if k >= 0:
                t = c
                n_prev = k
                break
        if t < 0:
            break
        prev = (t - 1) % n_l
        nxt = (t + 1) % n_l
        if closed and (t == 0 or t == n_l - 1):
            shift = _reroll(px, py, tol, st, sp, n_l, prev, tmp)
            total = (total + shift) % m
            _moments(px, py, cs)
            t = 1
            prev = 0
            nxt = 2 % n_l
        cut = st[t] + n_prev
        sp[prev] = cut
        st[nxt] = cut
        _delete(st, n_l, t)
        _delete(sp, n_l, t)
        n_l -= 1
    if n_l != n_before:
        total = (total + _refine(px, py, tol, cs, st, sp, n_l, closed, 8, tmp)) % m
    return st[:n_l].copy(), sp[:n_l].copy(), total


segment = _jit(segment_py)
