"""split-and-merge's segmentation as NumPy code, before the numba kernel (reference for tests).

``_normals_offsets``, ``_split``, ``_pair_excess``, ``_reroll``, ``_absorbable``,
``_absorb_short``, ``_refine_boundaries`` and the body of ``split_and_merge`` as they were in
``symloc.features.split_and_merge`` at main bad82ae, verbatim; :func:`split_and_merge_numpy`
starts with the module's own ``_closed_start`` and ends with its ``_line_set`` (the roll
and the final fits, unchanged). The kernels of
:mod:`symloc.features.split_kernels` must give the same lines, bit for bit.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.features.split_and_merge import (
    LineSet,
    _closed_start,
    _line_set,
    _Moments,
    _rolled,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


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


def _split(
    p: FloatArray, tol: FloatArray, first_cut: int | None, mom: _Moments | None = None
) -> list[int]:
    """Split at the farthest point from the chord, recursively; returns sorted cut indices.

    A segment is kept whole when its TLS line holds every interior point within tolerance;
    otherwise it is cut at the interior point farthest from its chord. (Testing the chord
    itself, as the textbook does, over-splits: a chord between two noisy end points is tilted
    by their noise.) All segments of one recursion level are processed together.
    """
    if mom is None:
        mom = _Moments(p)
    m = p.shape[0]
    cuts = [0, m - 1]
    if first_cut is not None and 0 < first_cut < m - 1:
        cuts.append(first_cut)
        seg_i = np.array([0, first_cut], dtype=np.intp)
        seg_j = np.array([first_cut, m - 1], dtype=np.intp)
    else:
        seg_i = np.array([0], dtype=np.intp)
        seg_j = np.array([m - 1], dtype=np.intp)
    cs = mom.cs
    # contiguous coordinate columns: gathering from them is much cheaper than from rows of p
    px = np.ascontiguousarray(p[:, 0])
    py = np.ascontiguousarray(p[:, 1])
    new_cuts = []
    while seg_i.size:
        keep = seg_j - seg_i >= 2
        if not keep.all():
            seg_i, seg_j = seg_i[keep], seg_j[keep]
            if seg_i.size == 0:
                break
        n_in = seg_j - seg_i - 1
        ends = n_in.cumsum()
        first = ends - n_in
        idx = np.arange(int(ends[-1])) - (first - seg_i - 1).repeat(n_in)
        xi = px[idx]
        yi = py[idx]
        ti = tol[idx]
        # the segment's own line decides whether it is one wall (interior points: the moment
        # sums of [seg_i + 1, seg_j) never wrap)
        nx, ny, off = _normals_offsets(cs[:, seg_j] - cs[:, seg_i + 1])
        res = np.abs(xi * nx.repeat(n_in) + yi * ny.repeat(n_in) - off.repeat(n_in)) / ti
        bent = np.maximum.reduceat(res, first) > 1.0
        if not bent.all():
            if not bent.any():
                break
            # only the bent segments are cut: keep their points
            sel = bent.repeat(n_in)
            idx, xi, yi, ti = idx[sel], xi[sel], yi[sel], ti[sel]
            seg_i, seg_j, n_in = seg_i[bent], seg_j[bent], n_in[bent]
            ends = n_in.cumsum()
            first = ends - n_in
        # cut at the interior point farthest from the chord
        ax, ay = px[seg_i], py[seg_i]
        dx, dy = px[seg_j] - ax, py[seg_j] - ay
        length = np.hypot(dx, dy)
        qx = xi - ax.repeat(n_in)
        qy = yi - ay.repeat(n_in)
        cross = np.abs(dx.repeat(n_in) * qy - dy.repeat(n_in) * qx)
        safe = length > 1e-12
        if safe.all():
            dist = cross / length.repeat(n_in)
        else:
            dist = np.where(
                safe.repeat(n_in),
                cross / np.where(safe, length, 1.0).repeat(n_in),
                np.hypot(qx, qy),
            )
        ratio = dist / ti
        best = np.maximum.reduceat(ratio, first)
        split = best > 1.0
        if not split.any():
            break
        # first index of each segment's maximum
        cand = np.where(ratio == best.repeat(n_in), np.arange(idx.size), idx.size)
        arg = np.minimum.reduceat(cand, first)
        k = idx[arg[split]]
        new_cuts.append(k)
        seg_i, seg_j = (
            np.concatenate((seg_i[split], k)),
            np.concatenate((k, seg_j[split])),
        )
    if new_cuts:
        cuts.extend(np.concatenate(new_cuts).tolist())
    return sorted(cuts)


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


def split_and_merge_numpy(
    points: ArrayLike, tolerance: ArrayLike, *, closed: bool = False, min_points: int = 2
) -> LineSet:
    """``split_and_merge`` as it was (valid input assumed: no argument checks)."""
    p = np.asarray(points, dtype=np.float64)
    m = p.shape[0]
    tol = np.broadcast_to(np.asarray(tolerance, dtype=np.float64), (m,))
    p, tol, roll, first_cut = _closed_start(p, tol, closed=closed)
    mom = _Moments(p)
    cuts = _split(p, tol, first_cut, mom)

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
    return _line_set(p, tol, st, sp, roll=int(roll), closed=bool(closed), mom=mom)
