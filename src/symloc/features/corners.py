"""Corners as intersections of adjacent lines (Section 4.1: "extract the intersection points of
adjacent line segments as corner points").

A corner between two lines that follow each other in scan order is only *seen* when it lies in
the gap between the last point of the first line and the first point of the next: ahead of the
first line's end, behind the next line's start, and no farther from either than the gap between
them allows for the angle the lines make. An occlusion (a box, the edge of an L-shaped room)
joins two lines whose intersection lies elsewhere; such a corner is marked not seen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.features.split_and_merge import LineSet

__all__ = ["Corners", "adjacent_corners", "intersect_lines"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Corners:
    """Corners between consecutive lines.

    Attributes
    ----------
    points : ndarray of shape (K, 2)
        Intersection of line ``pairs[k, 0]`` with line ``pairs[k, 1]`` [m] (NaN if parallel).
    pairs : ndarray of shape (K, 2)
        Indices of the two lines.
    turn : ndarray of shape (K,)
        Signed turning angle [rad] from the first line's direction to the second's; positive
        (counter-clockwise) at the convex corners of a room seen from inside by a
        counter-clockwise scanner.
    seen : ndarray of shape (K,)
        True when the corner lies in the gap between the two lines' end points (see the
        module docstring); False at occlusions and for parallel lines.
    gap : ndarray of shape (K,)
        Distance [m] between the first line's last point and the next line's first point.
    """

    points: FloatArray
    pairs: NDArray[np.intp]
    turn: FloatArray
    seen: NDArray[np.bool_]
    gap: FloatArray

    def __len__(self) -> int:
        return int(self.pairs.shape[0])


def intersect_lines(
    normals_a: ArrayLike, offsets_a: ArrayLike, normals_b: ArrayLike, offsets_b: ArrayLike
) -> FloatArray:
    """Intersections of lines ``n_a @ p = o_a`` and ``n_b @ p = o_b``, vectorised.

    Parameters
    ----------
    normals_a, normals_b : array of shape (K, 2)
        Unit normals.
    offsets_a, offsets_b : array of shape (K,)
        Offsets [m].

    Returns
    -------
    ndarray of shape (K, 2)
        Intersection points [m]; NaN rows for (numerically) parallel lines.
    """
    na = np.asarray(normals_a, dtype=np.float64).reshape(-1, 2)
    nb = np.asarray(normals_b, dtype=np.float64).reshape(-1, 2)
    oa = np.asarray(offsets_a, dtype=np.float64).reshape(-1)
    ob = np.asarray(offsets_b, dtype=np.float64).reshape(-1)
    det = na[:, 0] * nb[:, 1] - na[:, 1] * nb[:, 0]
    ok = np.abs(det) > 1e-9
    safe = np.where(ok, det, 1.0)
    x = (oa * nb[:, 1] - ob * na[:, 1]) / safe
    y = (na[:, 0] * ob - nb[:, 0] * oa) / safe
    out = np.stack([x, y], axis=1)
    out[~ok] = np.nan
    return out


def adjacent_corners(lines: LineSet, *, tolerance: ArrayLike = 0.0) -> Corners:
    """Corners between each line and the next one in scan order.

    Parameters
    ----------
    lines : LineSet
        From :func:`symloc.features.split_and_merge`. For a closed contour the last line's
        corner with the first line is included (K = L), otherwise K = L - 1.
    tolerance : float or array of shape (K,)
        Slack [m] for the "seen" test (the range noise at the corner).

    Returns
    -------
    Corners
    """
    n_lines = len(lines)
    if n_lines < 2:
        empty = np.zeros((0, 2))
        return Corners(
            empty, np.zeros((0, 2), np.intp), np.zeros(0), np.zeros(0, bool), np.zeros(0)
        )
    a = np.arange(n_lines if lines.closed and n_lines > 2 else n_lines - 1)
    b = (a + 1) % n_lines
    pts = intersect_lines(lines.normals[a], lines.offsets[a], lines.normals[b], lines.offsets[b])
    da, db = lines.directions[a], lines.directions[b]
    cross = da[:, 0] * db[:, 1] - da[:, 1] * db[:, 0]
    turn = np.arctan2(cross, da[:, 0] * db[:, 0] + da[:, 1] * db[:, 1])
    end_a = lines.endpoints[a, 1]
    start_b = lines.endpoints[b, 0]
    g = start_b - end_a
    gap = np.sqrt(g[:, 0] * g[:, 0] + g[:, 1] * g[:, 1])
    tol = np.asarray(tolerance, dtype=np.float64)
    if tol.shape != a.shape:
        tol = np.broadcast_to(tol, a.shape)
    sin_phi = np.abs(np.sin(turn))
    with np.errstate(invalid="ignore", divide="ignore"):
        reach = gap / np.maximum(sin_phi, 1e-6) + tol
        # a point within tol of the next wall may sit up to tol / sin(phi) past the corner
        slack = tol / np.maximum(sin_phi, 0.1)
        pa = pts - end_a
        bp = start_b - pts
        ahead_a = pa[:, 0] * da[:, 0] + pa[:, 1] * da[:, 1] >= -slack
        behind_b = bp[:, 0] * db[:, 0] + bp[:, 1] * db[:, 1] >= -slack
        near = (np.sqrt(pa[:, 0] * pa[:, 0] + pa[:, 1] * pa[:, 1]) <= reach) & (
            np.sqrt(bp[:, 0] * bp[:, 0] + bp[:, 1] * bp[:, 1]) <= reach
        )
    seen = np.isfinite(pts[:, 0]) & ahead_a & behind_b & near
    return Corners(pts, np.stack([a, b], axis=1).astype(np.intp), turn, seen, gap)
