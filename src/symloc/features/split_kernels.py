"""Compiled loops of split-and-merge's segmentation (numba, cached on disk).

Split-and-merge's decisions are integers -- where a run of points is cut into lines -- taken
by many small tests (one TLS fit and one residual pass per segment). In NumPy each test is a
few dozen array calls on a few dozen points, so on an 800-point scan the per-call overhead is
most of the cost. The kernels here take the same decisions in one compiled loop:

- :func:`split_cuts`: the recursive split of split-and-merge (before this kernel, ``_split``).

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

__all__ = ["split_cuts", "split_cuts_py"]


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
