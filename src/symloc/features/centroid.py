"""Centroids of a scan: the paper's mean of points (eq. 3-4) and the area centroid.

The paper's geometric centroid (Section 4.2, eq. 3-4) is the plain mean of the scan points.
Because a scanner samples at equal angles, walls near the robot get many more points than far
walls, so the mean is pulled toward the near walls (the paper's Figure 7). The area centroid of
the polygon that joins the points in scan order does not depend on how densely the walls were
sampled: for a robot inside a convex room it is the centroid of the room itself, up to the
small corners cut off between two sparse points.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError

__all__ = ["CENTROID_METHODS", "area_centroid", "centroid", "mean_centroid", "polygon_area"]

FloatArray = NDArray[np.float64]

CENTROID_METHODS = ("mean", "area")


def mean_centroid(points: ArrayLike) -> FloatArray:
    """Mean of the points, the paper's eq. 3-4.

    Parameters
    ----------
    points : array of shape (M, 2)
        x, y [m].

    Returns
    -------
    ndarray of shape (2,)
        The centroid [m]; NaN when there are no points.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if p.shape[0] == 0:
        return np.full(2, np.nan)
    return np.asarray(p.mean(axis=0), dtype=np.float64)


def polygon_area(points: ArrayLike) -> float:
    """Signed area [m^2] of the closed polygon through the points in order (shoelace).

    Positive when the points run counter-clockwise, as a counter-clockwise scanner's do.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if p.shape[0] < 3:
        return 0.0
    x, y = p[:, 0], p[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    return float(0.5 * np.sum(x * yn - xn * y))


def area_centroid(points: ArrayLike) -> tuple[FloatArray, float]:
    """Area centroid of the closed polygon through the points in scan order.

    Parameters
    ----------
    points : array of shape (M, 2)
        Polygon vertices [m] in order (the scan points of a 360-degree scan).

    Returns
    -------
    centroid : ndarray of shape (2,)
        ``C = 1 / (6 A) * sum (p_i + p_{i+1}) (p_i x p_{i+1})`` [m]. Falls back to the mean of
        the points when the polygon has (almost) no area; NaN when there are no points.
    area : float
        Signed area [m^2].
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if p.shape[0] == 0:
        return np.full(2, np.nan), 0.0
    if p.shape[0] < 3:
        return p.mean(axis=0), 0.0
    q = np.concatenate((p[1:], p[:1]))
    cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    area = 0.5 * float(cross.sum())
    scale = float(np.max(np.abs(p))) if p.size else 0.0
    if abs(area) <= 1e-12 * max(scale * scale, 1e-12):
        return p.mean(axis=0), area
    c = ((p + q) * cross[:, None]).sum(axis=0) / (6.0 * area)
    return c, area


def centroid(points: ArrayLike, method: str = "area") -> FloatArray:
    """Centroid of scan points by name: ``"mean"`` (eq. 3-4) or ``"area"`` (scan polygon).

    Raises
    ------
    ValueError
        (as :class:`symloc.errors.ConfigurationError`) for an unknown method.
    """
    if method == "mean":
        return mean_centroid(points)
    if method == "area":
        return area_centroid(points)[0]
    raise ConfigurationError(f"centroid: expected one of {CENTROID_METHODS}, got {method!r}")
