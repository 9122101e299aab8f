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
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any, cast

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["endpoint_table_sum", "n_threads", "split_over_threads"]

#: Particle-beam pairs below which one thread does the whole update (threads cost ~20 us).
PARALLEL_MIN_PAIRS = 200_000

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


def _jit(fn: Callable[..., Any]) -> Callable[..., Any]:
    return cast(Callable[..., Any], numba.njit(cache=True, nogil=True, error_model="numpy")(fn))


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
