"""Compiled inner loops of the particle filter (numba, cached on disk).

The filter's hot loops -- one table lookup per particle-beam pair, clustering the particles
into bins -- are written once here as plain Python over arrays and compiled by numba
(``cache=True``: the machine code is written beside this file on the first call and loaded
from there afterwards, so only the very first call in a fresh install pays the compile).
Every kernel releases the GIL, so :func:`split_over_threads` runs it on several cores over
disjoint blocks of particles.

Each kernel repeats, operation for operation, the NumPy expression it replaces (the same
float32 rounding of end points, the same truncation to cells, float64 sums of float32 table
values in particle order), so the results are bit-identical to the vectorised code; the tests
check that on random inputs against the pure-Python definitions kept here as ``*_py``.

Each kernel is a :class:`symloc.mcl.aot.Kernel`: the kernels of the per-scan path run from
their ahead-of-time build when one was made (``python -m symloc.mcl.aot_build``; then a tracking
process does not load numba at all), numba's JIT otherwise; numba is imported on the first
call that needs it.
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.mcl.aot import Kernel

__all__ = ["endpoint_table_sum", "n_threads", "split_over_threads"]

#: Particle-beam pairs below which one thread does the whole update (threads cost ~20 us).
PARALLEL_MIN_PAIRS = 200_000

#: Poses processed together when counting matches (each is given up on its own, and the
#: block stays large enough for its inner loops to run dense as poses drop out).
_CBLOCK = 512

#: Particles processed together by the table-sum kernel (its inner, vectorised loop).
_BLOCK = 256

_POOL: ThreadPoolExecutor | None = None
_POOL_LOCK = threading.Lock()


def n_threads() -> int:
    """Cores this process may run on (its CPU affinity), at most 8."""
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        n = os.cpu_count() or 1
    return max(1, min(8, n))


def _pool() -> ThreadPoolExecutor:
    global _POOL
    with _POOL_LOCK:
        if _POOL is None:
            _POOL = ThreadPoolExecutor(max_workers=n_threads(), thread_name_prefix="symloc-k")
        return _POOL


def split_over_threads(n: int, pairs: int, run: Callable[[int, int], None]) -> None:
    """Call ``run(start, stop)`` over blocks covering ``range(n)``, on several cores if large.

    ``pairs`` is the amount of work (particle-beam pairs); below :data:`PARALLEL_MIN_PAIRS`, or
    with one core, ``run(0, n)`` is called in this thread. ``run`` must release the GIL (a
    numba ``nogil`` kernel) and write only to its own block.
    """
    k = n_threads()
    if k == 1 or pairs < PARALLEL_MIN_PAIRS or n < 2 * k:
        run(0, n)
        return
    edges = [n * i // k for i in range(k + 1)]
    futures = [_pool().submit(run, edges[i], edges[i + 1]) for i in range(1, k)]
    run(edges[0], edges[1])
    for f in futures:
        f.result()


#: Kernels that other kernels call: numba resolves such a name when it compiles the caller, so
#: once numba is loaded these module names are its dispatchers (:func:`jit_callees`).
_CALLEES = ("np_mod", "_find_jit", "_leaf_sum", "pairwise_sum", "bilinear")
_callees_bound = False


def numba_jit(fn: Callable[..., Any]) -> Any:
    """numba's dispatcher of ``fn`` with the kernels' options (cached on disk, GIL released,
    NumPy's error model), made now (imports numba): for compiled loops off the per-scan path
    that call one another (the global search's)."""
    import numba

    return numba.njit(cache=True, nogil=True, error_model="numpy")(fn)


def _make_jit(fn: Callable[..., Any]) -> Any:
    dispatcher = numba_jit(fn)
    jit_callees()
    return dispatcher


def jit_callees() -> None:
    """Bind the names of the kernels that other kernels call to numba's dispatchers (before
    numba compiles a caller; imports numba)."""
    global _callees_bound
    if _callees_bound:
        return
    _callees_bound = True
    g = globals()
    for name in _CALLEES:
        k = g[name]
        if isinstance(k, Kernel):
            g[name] = k.dispatcher


def _jit(fn: Callable[..., Any]) -> Kernel:
    return Kernel(fn, _make_jit)


def endpoint_table_sum_py(
    table: NDArray[np.float32],
    width: int,
    height: int,
    poses: NDArray[np.float64],
    inv_res: float,
    bx: NDArray[np.float32],
    by: NDArray[np.float32],
    start: int,
    stop: int,
    out: NDArray[np.float64],
) -> None:
    """``out[i] = sum_j table[cell(i, j)]`` for particles ``start <= i < stop``.

    ``table`` is a padded table flattened, ``(height * width,)`` (``width = W + 2``);
    ``poses (N, 3)`` laser poses in the grid frame [m, rad]; ``bx, by (B,)`` the beam end
    points in the laser frame in cell units (float32). The end point of beam ``j`` from
    particle ``i`` is ``(lx + c bx - s by, ly + s bx + c by)`` in float32 with ``c, s`` the
    float32 cosine and sine of the heading and ``lx, ly`` the position in cells, shifted by
    the one-cell border, clipped into the padded table and truncated to a cell, exactly as
    :func:`symloc.mcl.likelihood_field.endpoint_flat_indices` does.
    """
    one = np.float32(1.0)
    zero = np.float32(0.0)
    xmax = np.float32(width - 1)
    ymax = np.float32(height - 1)
    nb = bx.shape[0]
    # Blocks of particles, beams outside and particles inside: each particle's sum still adds
    # its beams in order (bit-identical), but the block's sums are independent, so the inner
    # loop vectorises (gathers) instead of waiting on one chain of float64 additions.
    cb = np.empty(_BLOCK, dtype=np.float32)
    sb = np.empty(_BLOCK, dtype=np.float32)
    xb = np.empty(_BLOCK, dtype=np.float32)
    yb = np.empty(_BLOCK, dtype=np.float32)
    acc = np.empty(_BLOCK, dtype=np.float64)
    cell = np.empty(_BLOCK, dtype=np.uint32)
    for b0 in range(start, stop, _BLOCK):
        m = min(_BLOCK, stop - b0)
        for k in range(m):
            th = poses[b0 + k, 2]
            px = np.float32(poses[b0 + k, 0] * inv_res)
            py = np.float32(poses[b0 + k, 1] * inv_res)
            ck = np.float32(math.cos(th))
            sk = np.float32(math.sin(th))
            if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(ck)):
                px = np.float32(-1e30)  # a pose that is not a number reads the off-map border
                py = np.float32(-1e30)
                ck = zero
                sk = zero
            cb[k] = ck
            sb[k] = sk
            xb[k] = px
            yb[k] = py
            acc[k] = 0.0
        for j in range(nb):
            bxj = bx[j]
            byj = by[j]
            # cells of the block's end points (SIMD), then the table reads (scalar loads:
            # hardware gathers are slower than loads on many current cores)
            for k in range(m):
                x = cb[k] * bxj - sb[k] * byj
                x = x + xb[k]
                y = sb[k] * bxj + cb[k] * byj
                y = y + yb[k]
                x = min(max(x + one, zero), xmax)
                y = min(max(y + one, zero), ymax)
                cell[k] = np.uint32(np.int32(y) * np.int32(width) + np.int32(x))
            for k in range(m):
                acc[k] += table[cell[k]]
        for k in range(m):
            out[b0 + k] = acc[k]


endpoint_table_sum = _jit(endpoint_table_sum_py)


def np_mod_py(a: float, b: float) -> float:
    """NumPy's float remainder ``np.mod(a, b)`` (the sign of ``b``), operation for operation."""
    mod: float = np.fmod(a, b)  # exact, as C fmod
    if mod != 0.0:
        if (b < 0.0) != (mod < 0.0):
            mod += b
    else:
        mod = np.copysign(0.0, b)
    return mod


np_mod = _jit(np_mod_py)


def wrap_angle_py(a: float) -> float:
    """:func:`symloc.geometry.wrap_angle` of one angle, bit for bit."""
    m: float = np_mod(math.pi - a, 2.0 * math.pi)
    return math.pi - m


wrap_angle = _jit(wrap_angle_py)


def _find(parent: NDArray[np.int64], u: int) -> int:
    while parent[u] != u:
        parent[u] = parent[parent[u]]
        u = parent[u]
    return u


_find_jit = _jit(_find)


def kld_stop_py(
    particles: NDArray[np.float64],
    bin_xy: float,
    bin_angle: float,
    n_angle: int,
    pf_err: float,
    z: float,
    min_particles: int,
    max_particles: int,
) -> int:
    """How many of the samples ``particles (N, 3)`` (drawn in this order) KLD-sampling keeps;
    -1 when a pose is not finite (the caller then takes the NumPy path).

    :func:`symloc.mcl.kld_sampling.kld_stop_index` of
    :func:`symloc.mcl.clustering.bin_keys`, in one pass that stops where it does: the same
    bins (``floor(x / bin_xy), floor(y / bin_xy), floor((theta + pi) / bin_angle) mod
    n_angle``, keyed as ``bin_keys`` keys them) counted in an open-addressing hash table, and
    the bound of :func:`~symloc.mcl.kld_sampling.kld_sample_count` with the same float
    operations in the same order, evaluated when the count of bins grows.
    """
    n = particles.shape[0]
    cap = 16
    while cap < 2 * n:
        cap *= 2
    mask = cap - 1
    slot_key = np.empty(cap, dtype=np.int64)
    used = np.zeros(cap, dtype=np.bool_)
    off = np.int64(1) << np.int64(25)
    k = 0
    bound = np.int64(max_particles)  # k <= 1 gives max_particles
    for i in range(n):
        x = particles[i, 0]
        y = particles[i, 1]
        t = particles[i, 2]
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(t)):
            return -1
        b0 = np.int64(math.floor(x / bin_xy))
        b1 = np.int64(math.floor(y / bin_xy))
        b2 = np.int64(math.floor((t + math.pi) / bin_angle)) % n_angle
        key = ((b0 + off) << np.int64(32)) | ((b1 + off) << np.int64(6)) | b2
        h = (key * np.int64(-7046029254386353131)) >> np.int64(20)
        s = h & mask
        while used[s] and slot_key[s] != key:
            s = (s + 1) & mask
        if not used[s]:
            used[s] = True
            slot_key[s] = key
            k += 1
            kk = np.float64(k)
            if kk <= 1.0:
                bound = np.int64(max_particles)
            else:
                km1 = max(kk - 1.0, 1.0)
                b = 2.0 / (9.0 * km1)
                xx = 1.0 - b + math.sqrt(b) * z
                nb = np.ceil(km1 / (2.0 * pf_err) * xx * xx * xx)
                nb = min(max(nb, np.float64(min_particles)), np.float64(max_particles))
                bound = np.int64(nb)
        if i + 1 > bound:
            return i + 1
    return int(n)


kld_stop = _jit(kld_stop_py)


def bin_components_py(
    particles: NDArray[np.float64],
    bin_xy: float,
    bin_angle: float,
    n_angle: int,
    labels: NDArray[np.int64],
) -> int:
    """Cluster particles ``(N, 3)`` by touching histogram bins; returns the cluster count.

    Bins are ``floor(x / bin_xy), floor(y / bin_xy), floor((theta + pi) / bin_angle) mod
    n_angle``; two occupied bins touch when they differ by at most one in each index (the
    heading index wraps). ``labels (N,)`` receives each particle's cluster, numbered in the
    order of the smallest bin key in the cluster -- the numbering
    :func:`symloc.mcl.clustering.cluster_particles` got from sorted unique keys and
    ``scipy.sparse.csgraph.connected_components``. Linear in N: bins in an open-addressing
    hash table, clusters by union-find.
    """
    n = particles.shape[0]
    bx = np.empty(n, dtype=np.int64)
    by = np.empty(n, dtype=np.int64)
    bt = np.empty(n, dtype=np.int64)
    for i in range(n):
        bx[i] = np.int64(math.floor(particles[i, 0] / bin_xy))
        by[i] = np.int64(math.floor(particles[i, 1] / bin_xy))
        bt[i] = np.int64(math.floor((particles[i, 2] + math.pi) / bin_angle)) % n_angle
    lo0 = bx.min() - 1
    lo1 = by.min() - 1
    span1 = by.max() - lo1 + 2
    cap = 16
    while cap < 2 * n:
        cap *= 2
    mask = cap - 1
    slot_key = np.full(cap, -1, dtype=np.int64)
    slot_bin = np.empty(cap, dtype=np.int64)
    bin_key = np.empty(n, dtype=np.int64)
    n_bins = 0
    for i in range(n):
        key = ((bx[i] - lo0) * span1 + (by[i] - lo1)) * n_angle + bt[i]
        h = (key * np.int64(-7046029254386353131)) >> np.int64(20)
        s = h & mask
        while slot_key[s] != -1 and slot_key[s] != key:
            s = (s + 1) & mask
        if slot_key[s] == -1:
            slot_key[s] = key
            slot_bin[s] = n_bins
            bin_key[n_bins] = key
            n_bins += 1
        labels[i] = slot_bin[s]
    parent = np.arange(n_bins)
    for u in range(n_bins):
        key = bin_key[u]
        ub_t = key % n_angle
        ub_xy = key // n_angle
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                for dt in range(-1, 2):
                    if dx < 0 or (dx == 0 and (dy < 0 or (dy == 0 and dt <= 0))):
                        continue  # each undirected edge once
                    nkey = (ub_xy + dx * span1 + dy) * n_angle + (ub_t + dt) % n_angle
                    h = (nkey * np.int64(-7046029254386353131)) >> np.int64(20)
                    s = h & mask
                    while slot_key[s] != -1 and slot_key[s] != nkey:
                        s = (s + 1) & mask
                    if slot_key[s] == nkey:
                        ra = _find_jit(parent, u)
                        rb = _find_jit(parent, slot_bin[s])
                        if ra != rb:
                            parent[max(ra, rb)] = min(ra, rb)
    # clusters numbered by their smallest key
    root_min = np.full(n_bins, np.iinfo(np.int64).max, dtype=np.int64)
    for u in range(n_bins):
        r = _find_jit(parent, u)
        parent[u] = r
        if bin_key[u] < root_min[r]:
            root_min[r] = bin_key[u]
    n_comp = 0
    for u in range(n_bins):
        if parent[u] == u:
            n_comp += 1
    roots = np.empty(n_comp, dtype=np.int64)
    mins = np.empty(n_comp, dtype=np.int64)
    c = 0
    for u in range(n_bins):
        if parent[u] == u:
            roots[c] = u
            mins[c] = root_min[u]
            c += 1
    order = np.argsort(mins)
    comp_of_root = np.empty(n_bins, dtype=np.int64)
    for rank in range(n_comp):
        comp_of_root[roots[order[rank]]] = rank
    for i in range(n):
        labels[i] = comp_of_root[parent[labels[i]]]
    return n_comp


bin_components = _jit(bin_components_py)


def cluster_sums_py(
    particles: NDArray[np.float64],
    weights: NDArray[np.float64],
    total: float,
    labels: NDArray[np.int64],
    n: int,
    out: NDArray[np.float64],
) -> None:
    """First moments of each cluster, as ``np.bincount`` adds them (particle order).

    ``out (7, n)`` receives rows ``wsum, count, mean x, mean y, mean cos, mean sin`` (the means
    over weights normalised within the cluster; equal weights where the cluster's sum is 0)
    and row 6 unused here.
    """
    out[:, :] = 0.0
    m = particles.shape[0]
    for i in range(m):
        c = labels[i]
        out[0, c] += weights[i] / total
        out[1, c] += 1.0
    for i in range(m):
        c = labels[i]
        w = weights[i] / total
        ws = out[0, c]
        wn = w / ws if ws > 0.0 else 1.0 / out[1, c]
        th = particles[i, 2]
        out[2, c] += wn * particles[i, 0]
        out[3, c] += wn * particles[i, 1]
        out[4, c] += wn * math.cos(th)
        out[5, c] += wn * math.sin(th)


cluster_sums = _jit(cluster_sums_py)


def cluster_moments_py(
    particles: NDArray[np.float64],
    weights: NDArray[np.float64],
    total: float,
    labels: NDArray[np.int64],
    first: NDArray[np.float64],
    mean_theta: NDArray[np.float64],
    out: NDArray[np.float64],
) -> None:
    """Second moments ``out (5, n)``: xx, yy, xy, x-theta, y-theta of each cluster.

    ``first`` is :func:`cluster_sums`'s output, ``mean_theta (n,)`` the clusters' circular mean
    headings; headings are unwrapped around it (``pi - mod(pi - (theta - mean), 2 pi)``).
    """
    out[:, :] = 0.0
    m = particles.shape[0]
    two_pi = 2.0 * math.pi
    for i in range(m):
        c = labels[i]
        w = weights[i] / total
        ws = first[0, c]
        wn = w / ws if ws > 0.0 else 1.0 / first[1, c]
        dx = particles[i, 0] - first[2, c]
        dy = particles[i, 1] - first[3, c]
        dt = math.pi - np_mod(math.pi - (particles[i, 2] - mean_theta[c]), two_pi)
        out[0, c] += wn * dx * dx
        out[1, c] += wn * dy * dy
        out[2, c] += wn * dx * dy
        out[3, c] += wn * dx * dt
        out[4, c] += wn * dy * dt


cluster_moments = _jit(cluster_moments_py)


def move_diff_py(
    particles: NDArray[np.float64],
    noise: NDArray[np.float64],
    rot1: float,
    trans: float,
    rot2: float,
    s_r1: float,
    s_tr: float,
    s_r2: float,
    out: NDArray[np.float64],
) -> None:
    """The differential motion model's sample for every particle (Thrun et al., Table 5.6).

    ``noise (3, N)`` standard normal draws; ``out (N, 3)`` (may be ``particles``) receives
    ``x + tr cos(theta + r1), y + tr sin(theta + r1), wrap(theta + r1 + r2)`` with
    ``r1 = rot1 - s_r1 n0``, ``tr = trans - s_tr n1``, ``r2 = rot2 - s_r2 n2``: the
    expressions of :func:`symloc.mcl.motion_model.sample_motion_model_odometry`, bit for bit.
    """
    for i in range(particles.shape[0]):
        r1_hat = rot1 - s_r1 * noise[0, i]
        tr_hat = trans - s_tr * noise[1, i]
        r2_hat = rot2 - s_r2 * noise[2, i]
        heading = particles[i, 2] + r1_hat
        x = particles[i, 0] + tr_hat * math.cos(heading)
        y = particles[i, 1] + tr_hat * math.sin(heading)
        th = heading + r2_hat
        out[i, 0] = x
        out[i, 1] = y
        out[i, 2] = math.pi - np_mod(math.pi - th, 2.0 * math.pi)


move_diff = _jit(move_diff_py)


def count_within_py(
    table: NDArray[np.float32],
    width: int,
    height: int,
    poses: NDArray[np.float64],
    inv_res: float,
    bx: NDArray[np.float32],
    by: NDArray[np.float32],
    tol: NDArray[np.float32],
    pre: int,
    total: int,
    need: int,
    start: int,
    stop: int,
    out: NDArray[np.float64],
) -> None:
    """``out[i] = (pre + #{j: table at end point j of pose i <= tol[j]}) / total``.

    End points as :func:`endpoint_table_sum_py` (the same cells, bit for bit); ``pre`` counts
    points known to pass everywhere, ``total`` is the number of points in all, so the value is
    ``np.count_nonzero(...) / total`` exactly. With ``need > 0`` a pose is given up as soon
    as it cannot reach ``need`` points any more (checked every 4 points): its value is then
    below ``need / total`` but not exact (exact for every pose that reaches it). The poses of
    a block still being counted are kept packed at its front, so the inner loops stay dense
    however many have been given up.
    """
    one = np.float32(1.0)
    zero = np.float32(0.0)
    xmax = np.float32(width - 1)
    ymax = np.float32(height - 1)
    nb = bx.shape[0]
    cb = np.empty(_CBLOCK, dtype=np.float32)
    sb = np.empty(_CBLOCK, dtype=np.float32)
    xb = np.empty(_CBLOCK, dtype=np.float32)
    yb = np.empty(_CBLOCK, dtype=np.float32)
    cnt = np.empty(_CBLOCK, dtype=np.int64)
    idx = np.empty(_CBLOCK, dtype=np.int64)
    cell = np.empty(_CBLOCK, dtype=np.uint32)
    last_th = math.nan  # the heading whose cosine and sine are held (NaN: none yet)
    last_c = one
    last_s = zero
    for b0 in range(start, stop, _CBLOCK):
        m = min(_CBLOCK, stop - b0)
        for k in range(m):
            th = poses[b0 + k, 2]
            px = np.float32(poses[b0 + k, 0] * inv_res)
            py = np.float32(poses[b0 + k, 1] * inv_res)
            if th != last_th:  # a lattice's block shares one heading: one cosine and sine
                last_th = th
                last_c = np.float32(math.cos(th))
                last_s = np.float32(math.sin(th))
            ck = last_c
            sk = last_s
            if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(ck)):
                px = np.float32(-1e30)
                py = np.float32(-1e30)
                ck = zero
                sk = zero
            cb[k] = ck
            sb[k] = sk
            xb[k] = px
            yb[k] = py
            cnt[k] = 0
            idx[k] = b0 + k
        for j in range(nb):
            bxj = bx[j]
            byj = by[j]
            tj = tol[j]
            for k in range(m):
                x = cb[k] * bxj - sb[k] * byj
                x = x + xb[k]
                y = sb[k] * bxj + cb[k] * byj
                y = y + yb[k]
                x = min(max(x + one, zero), xmax)
                y = min(max(y + one, zero), ymax)
                cell[k] = np.uint32(np.int32(y) * np.int32(width) + np.int32(x))
            for k in range(m):
                if table[cell[k]] <= tj:
                    cnt[k] += 1
            if need > 0 and (j & 3) == 3:
                # give up the poses that cannot reach need; pack the others at the front
                short = need - pre - (nb - 1 - j)
                kept = 0
                for k in range(m):
                    if cnt[k] < short:
                        out[idx[k]] = (cnt[k] + pre) / total
                    else:
                        cb[kept] = cb[k]
                        sb[kept] = sb[k]
                        xb[kept] = xb[k]
                        yb[kept] = yb[k]
                        cnt[kept] = cnt[k]
                        idx[kept] = idx[k]
                        kept += 1
                m = kept
                if m == 0:
                    break
        for k in range(m):
            out[idx[k]] = (cnt[k] + pre) / total


count_within = _jit(count_within_py)


def _leaf_sum_py(a: NDArray[np.float64], lo: int, n: int) -> float:
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0 = a[lo]
    r1 = a[lo + 1]
    r2 = a[lo + 2]
    r3 = a[lo + 3]
    r4 = a[lo + 4]
    r5 = a[lo + 5]
    r6 = a[lo + 6]
    r7 = a[lo + 7]
    i = 8
    while i < n - (n % 8):
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    out: float = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        out += a[lo + i]
        i += 1
    return out


_leaf_sum = _jit(_leaf_sum_py)


def pairwise_sum_py(a: NDArray[np.float64], lo: int, n: int) -> float:
    """``np.sum(a[lo:lo + n])`` for contiguous float64, bit for bit: NumPy's pairwise
    summation (eight partial sums in blocks of up to 128 values, halves above that; the
    halving recursion unrolled on an explicit stack)."""
    if n <= 128:
        leaf: float = _leaf_sum(a, lo, n)
        return leaf
    los = np.empty(64, dtype=np.int64)
    ns = np.empty(64, dtype=np.int64)
    phase = np.zeros(64, dtype=np.int64)
    vals = np.empty(64, dtype=np.float64)
    sp = 0
    vsp = 0
    los[0] = lo
    ns[0] = n
    while sp >= 0:
        m = ns[sp]
        if m <= 128:
            vals[vsp] = _leaf_sum(a, los[sp], m)
            vsp += 1
            sp -= 1
            continue
        n2 = m // 2
        n2 -= n2 % 8
        if phase[sp] == 0:
            phase[sp] = 1
            los[sp + 1] = los[sp]
            ns[sp + 1] = n2
            phase[sp + 1] = 0
            sp += 1
        elif phase[sp] == 1:
            phase[sp] = 2
            los[sp + 1] = los[sp] + n2
            ns[sp + 1] = m - n2
            phase[sp + 1] = 0
            sp += 1
        else:
            vals[vsp - 2] = vals[vsp - 2] + vals[vsp - 1]
            vsp -= 1
            sp -= 1
    total: float = vals[0]
    return total


pairwise_sum = _jit(pairwise_sum_py)


def bilinear_py(
    pad: NDArray[np.float32],
    width: int,
    height: int,
    ox: float,
    oy: float,
    res: float,
    x: NDArray[np.float64],
    y: NDArray[np.float64],
    d: NDArray[np.float64],
    gu: NDArray[np.float64],
    gv: NDArray[np.float64],
    with_gradient: bool,
) -> None:
    """Bilinear distance ``d`` (and its gradient ``gu, gv`` per metre) at world points ``x, y``
    on a padded field (flattened, ``height * width``) whose grid has an unrotated origin
    ``(ox, oy)``: :func:`symloc.mcl.scan_to_map._bilinear`'s expressions, bit for bit."""
    umax = width - 1.000001
    vmax = height - 1.000001
    for k in range(x.shape[0]):
        u = (x[k] - ox) / res - 0.5 + 1.0
        v = (y[k] - oy) / res - 0.5 + 1.0
        u = min(max(u, 0.0), umax)
        v = min(max(v, 0.0), vmax)
        i0 = np.int64(u)
        j0 = np.int64(v)
        fu = u - i0
        fv = v - j0
        base = j0 * width + i0
        d00 = np.float64(pad[base])
        d10 = np.float64(pad[base + 1])
        d01 = np.float64(pad[base + width])
        d11 = np.float64(pad[base + width + 1])
        d[k] = (1 - fv) * ((1 - fu) * d00 + fu * d10) + fv * ((1 - fu) * d01 + fu * d11)
        if with_gradient:
            gu[k] = ((1 - fv) * (d10 - d00) + fv * (d11 - d01)) / res
            gv[k] = ((1 - fu) * (d01 - d00) + fu * (d11 - d10)) / res


bilinear = _jit(bilinear_py)


def squared_distance_sum_py(
    pad: NDArray[np.float32],
    width: int,
    height: int,
    ox: float,
    oy: float,
    res: float,
    pts: NDArray[np.float64],
    c: float,
    s: float,
    tx: float,
    ty: float,
    buf: NDArray[np.float64],
) -> float:
    """``np.sum(d * d)`` of the bilinear distances of ``pts (N, 2)`` placed at the pose
    ``(tx, ty)`` with ``cos, sin = c, s`` (``x = c px - s py + tx``), bit for bit; ``buf``
    (N,) is scratch space."""
    n = pts.shape[0]
    x = np.empty(1)
    y = np.empty(1)
    dd = np.empty(1)
    for k in range(n):
        x[0] = c * pts[k, 0] - s * pts[k, 1] + tx
        y[0] = s * pts[k, 0] + c * pts[k, 1] + ty
        bilinear(pad, width, height, ox, oy, res, x, y, dd, dd, dd, False)
        buf[k] = dd[0] * dd[0]
    total: float = pairwise_sum(buf, 0, n)
    return total


squared_distance_sum = _jit(squared_distance_sum_py)
