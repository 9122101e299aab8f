"""The walls of one scan as the judgement sees them: contour runs and their fitted lines.

For display and diagnosis (figures, the ``symloc symmetry judge`` command): the same cut into
runs at gaps and the same split-and-merge with noise-derived tolerances that
:func:`symloc.symmetry.judge_symmetry` uses on an open contour.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.features.split_and_merge import LineSet, contour_runs, split_and_merge
from symloc.scan import LaserScan
from symloc.symmetry.config import SymmetryConfig

__all__ = ["ScanLines", "scan_lines"]


@dataclass(frozen=True, slots=True, eq=False)
class ScanLines:
    """Fitted lines of each contour run of a scan.

    Attributes
    ----------
    runs : ndarray of shape (R, 2)
        Half-open ranges into the scan's valid points (``stop`` may exceed the number of
        points when a run wraps around a full scan's end).
    lines : list of LineSet
        The lines of each run with at least two points (same order as ``runs``; runs of one
        point have no entry).
    segments : ndarray of shape (L, 2, 2)
        End points of every line [m], sensor frame (all runs together).
    n_points : ndarray of shape (L,)
        Points on each line.
    """

    runs: NDArray[np.intp]
    lines: list[LineSet]
    segments: NDArray[np.float64]
    n_points: NDArray[np.intp]


def scan_lines(scan: LaserScan, config: SymmetryConfig | None = None) -> ScanLines:
    """Cut a scan into runs at its gaps and fit lines to each run (split-and-merge, TLS).

    Parameters
    ----------
    scan : LaserScan
    config : SymmetryConfig, optional
        Tolerances and gap settings (default: ``SymmetryConfig()``).

    Returns
    -------
    ScanLines
        Empty (no runs, no lines) for a scan without valid points.

    Raises
    ------
    ConfigurationError
        If ``scan`` is not a LaserScan or ``config`` not a SymmetryConfig.
    """
    if not isinstance(scan, LaserScan):
        raise ConfigurationError(f"scan: expected a LaserScan, got {type(scan).__name__}")
    cfg = SymmetryConfig() if config is None else config
    if not isinstance(cfg, SymmetryConfig):
        raise ConfigurationError(f"config: expected a SymmetryConfig, got {type(cfg).__name__}")
    sp = scan.to_points()
    pts = sp.points
    m = pts.shape[0]
    n_beams = len(scan)
    full = scan.angle_increment * n_beams >= 2.0 * math.pi - 1.5 * scan.angle_increment
    runs = contour_runs(
        sp.indices,
        n_beams,
        wrap=full,
        max_dropout_beams=cfg.max_dropout_beams,
        no_return=scan.no_return_mask,
        max_blind_beams=cfg.max_blind_beams,
    )
    tol = cfg.point_tolerance(sp.ranges)
    closed = full and runs.shape[0] == 1 and int(runs[0, 1] - runs[0, 0]) == m and m >= 4
    lines: list[LineSet] = []
    for start, stop in runs:
        idx = np.arange(int(start), int(stop)) % m
        if idx.size >= 2:
            lines.append(split_and_merge(pts[idx], tol[idx], closed=closed))
    if lines:
        segments = np.concatenate([ls.endpoints for ls in lines])
        n_points = np.concatenate([ls.n_points for ls in lines]).astype(np.intp)
    else:
        segments = np.zeros((0, 2, 2))
        n_points = np.zeros(0, dtype=np.intp)
    return ScanLines(runs=runs, lines=lines, segments=segments, n_points=n_points)
