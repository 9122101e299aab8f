"""Final scan-to-map refinement: every node's scan aligned with the map of the whole run.

The front end matches each scan against a submap of its last few metres, and loop closures tie
a node to one older submap: walls seen from far apart are only as consistent as the chain of
submaps between the two views. After the pose graph is optimised, this step (in the spirit of
the global refinement of Olson's and Hess et al.'s pipelines, as a scan-to-map bundle) builds
one map of the end points of *all* node scans at their optimised poses, aligns each node's
scan with it, and adds the result to the graph as a prior on the node with the match's own
covariance (loose along the directions the scan does not constrain), then optimises again;
a few rounds let the submaps settle where every view of a wall agrees.

The map is a point density, not an occupancy grid: every end point is splatted bilinearly into
a grid of ``resolution`` cells, blurred with a Gaussian of ``sigma``, and divided by its local
maximum (within ``3 sigma``), so that every wall, seen once or a thousand times, is a ridge of
height 1 along the mean of its points. A scan is refined on it by
:func:`~symloc.slam.correlative_scan_matching.refine_pose` (Levenberg-Marquardt on the
bilinear table), from its current pose.

Memory: the density grid covers the map's bounding box (``max_cells`` at most; a larger map is
not refined and the result says so); building it holds three float32 grids of that size at
most, and splatting a band of rows at a time adds two float64 buffers of a million cells.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from symloc.geometry import compose
from symloc.slam.correlative_scan_matching import LikelihoodTable

__all__ = ["add_splat", "density_table", "nodes_in_map", "splat_points"]

FloatArray = NDArray[np.float64]


def splat_points(
    points: FloatArray, origin_xy: FloatArray, resolution: float, shape: tuple[int, int]
) -> NDArray[np.float32]:
    """Bilinear splat of ``points`` (M, 2) [m] into a ``shape`` (H, W) grid of counts.

    Cell ``(r, c)`` has its centre at ``origin_xy + ((c, r) + 0.5) * resolution``; each point
    adds weight 1 shared among its four nearest cell centres (points outside are dropped).
    """
    out = np.zeros(shape, dtype=np.float32)
    add_splat(out, points, origin_xy, resolution)
    return out


#: Grid cells splatted at once by :func:`add_splat` (two float64 buffers of this size).
_BAND_CELLS = 1 << 20


def add_splat(
    counts: NDArray[np.float32], points: FloatArray, origin_xy: FloatArray, resolution: float
) -> None:
    """Add the bilinear splat of ``points`` (M, 2) [m] to ``counts`` (H, W) in place.

    Each cell gets, in float64, its four corner sums in the order (0, 0), (1, 0), (0, 1),
    (1, 1), each summed over the points in their order, then rounded to float32 and added:
    what adding a full (H, W) float64 splat gives, computed a band of rows at a time so that
    the float64 buffers hold ``_BAND_CELLS`` cells, not the whole grid.
    """
    h, w = counts.shape
    u = (points - origin_xy) / resolution - 0.5
    i0 = np.floor(u).astype(np.intp)
    f = u - i0
    del u
    out = counts.reshape(-1)
    rows = max(1, _BAND_CELLS // max(w, 1))
    for r_lo in range(0, h, rows):
        r_hi = min(r_lo + rows, h)
        acc = np.zeros((r_hi - r_lo) * w, dtype=np.float64)
        for dc, dr in ((0, 0), (1, 0), (0, 1), (1, 1)):
            c = i0[:, 0] + dc
            r = i0[:, 1] + dr
            sel = np.flatnonzero((c >= 0) & (c < w) & (r >= r_lo) & (r < r_hi))
            fs = f[sel]
            wgt = (fs[:, 0] if dc else 1.0 - fs[:, 0]) * (fs[:, 1] if dr else 1.0 - fs[:, 1])
            acc += np.bincount((r[sel] - r_lo) * w + c[sel], weights=wgt, minlength=acc.size)
        out[r_lo * w : r_hi * w] += acc.astype(np.float32)


def density_table(
    point_sets: Callable[[], Iterable[FloatArray]],
    resolution: float,
    sigma: float,
    *,
    max_cells: int,
    min_weight: float = 1.0,
) -> LikelihoodTable | None:
    """The ridge-normalised point density of all points (see the module docstring).

    ``point_sets`` returns, each time it is called, the point sets (M_k, 2) [m] in the map
    frame (called twice: once for the bounding box, once to splat, so that no copy of all
    the points is kept). Cells whose local maximum of blurred weight is below ``min_weight``
    (a point or two: noise, people walking) get 0. Returns None when the bounding box needs
    more than ``max_cells`` cells or there are no points.
    """
    lo = np.full(2, np.inf)
    hi = np.full(2, -np.inf)
    for pts in point_sets():
        if pts.shape[0]:
            lo = np.minimum(lo, pts.min(axis=0))
            hi = np.maximum(hi, pts.max(axis=0))
    if not np.all(np.isfinite(lo)):
        return None
    pad = 4.0 * sigma + 2.0 * resolution
    origin = lo - pad
    w = math.ceil((hi[0] - lo[0] + 2 * pad) / resolution) + 1
    h = math.ceil((hi[1] - lo[1] + 2 * pad) / resolution) + 1
    if h * w > max_cells:
        return None
    counts = np.zeros((h, w), dtype=np.float32)
    batch: list[FloatArray] = []
    n = 0
    for pts in point_sets():
        batch.append(pts)
        n += pts.shape[0]
        if n >= 500_000:  # one splat per batch: bounded temporaries
            add_splat(counts, np.concatenate(batch), origin, resolution)
            batch, n = [], 0
    if n:
        add_splat(counts, np.concatenate(batch), origin, resolution)
    del batch
    blurred = ndimage.gaussian_filter(counts, sigma / resolution, mode="constant")
    del counts
    size = 2 * math.ceil(3.0 * sigma / resolution) + 1
    peak = ndimage.maximum_filter(blurred, size=size, mode="constant")
    # the blurred weight of one isolated point at its own cell, for the noise floor
    one = float(1.0 / (2.0 * math.pi * (sigma / resolution) ** 2))
    drop = peak < min_weight * one
    # the ridge-normalised density, in place of the blurred weight (three grids at the peak)
    np.divide(blurred, peak, out=blurred, where=~drop)
    del peak
    blurred[drop] = 0.0
    return LikelihoodTable(blurred, resolution, origin)


def nodes_in_map(poses: FloatArray, point_sets: Iterable[FloatArray]) -> Iterator[FloatArray]:
    """Each node's points (M_k, 2) moved into the map frame by its pose (3,) in ``poses``."""
    for pose, pts in zip(poses, point_sets, strict=True):
        if pts.shape[0] == 0:
            yield pts
            continue
        yield np.asarray(compose(pose, np.c_[pts, np.zeros(pts.shape[0])]))[:, :2]
