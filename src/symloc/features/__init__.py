"""Features of a laser scan: split-and-merge lines, corners, centroids (Section 4.1-4.2)."""

from __future__ import annotations

from symloc.features.centroid import (
    CENTROID_METHODS,
    area_centroid,
    centroid,
    mean_centroid,
    polygon_area,
)
from symloc.features.corners import Corners, adjacent_corners, intersect_lines
from symloc.features.split_and_merge import (
    LineSet,
    contour_gaps,
    contour_runs,
    fit_line_tls,
    split_and_merge,
)

__all__ = [
    "CENTROID_METHODS",
    "Corners",
    "LineSet",
    "adjacent_corners",
    "area_centroid",
    "centroid",
    "contour_gaps",
    "contour_runs",
    "fit_line_tls",
    "intersect_lines",
    "mean_centroid",
    "polygon_area",
    "split_and_merge",
]
