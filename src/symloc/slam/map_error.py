"""The map's own error, estimated from how well the scans that built it agree with it.

A map built by laser SLAM is as good as the poses its scans were drawn at. Where two parts of
a trip disagree (a submap placed a few centimetres off, matches the odometry gate refused), the
walls they drew do not coincide, and a scan aligned to the finished map lands where its own part
of the trip put the walls, not where the others did. So each node's scan is aligned again to
the finished map, from the pose SLAM gave it, with the same alignment and surface field the
localizer's claim gate uses (:func:`symloc.mcl.scan_to_map.match_scan_to_map`): the pose moves
by the map's local disagreement plus the alignment's own noise.

Every node moves by about the same vector on a consistent map: the surface field puts a wall
on the centre line of its band of cells, which is up to half a cell from the hits that drew it,
whatever the poses. That common shift (the median over the nodes) is removed; what remains,
node by node, is the disagreement. Nodes whose scan leaves a direction unconstrained (a
corridor) are left out: their move along it measures nothing.

The estimate is a position std [m] for the map as a whole: the 95th percentile of the nodes'
remaining moves divided by 2.45 (the 95 % radius of a circular 2-D Gaussian in stds), so that a
localizer adding it to every match's covariance covers the map's worst places at its
95 % ellipse. It cannot see an error that all scans share (a lidar that reads every range 1 %
short draws a consistent map 1 % small).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.grid.fields import surface_distance_field
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.mcl.scan_to_map import ScanMatchConfig, match_scan_to_map
from symloc.scan import LaserScan

__all__ = ["R95", "MapError", "estimate_map_error"]

FloatArray = NDArray[np.float64]

logger = logging.getLogger(__name__)

#: The 95 % radius of a circular 2-D Gaussian, in stds: sqrt(chi2.ppf(0.95, 2)).
R95 = math.sqrt(-2.0 * math.log(0.05))


@dataclass(frozen=True)
class MapError:
    """The map's own error as its scans tell it (see the module docstring).

    Attributes
    ----------
    std_xy : float
        Position std [m] of the map's walls: the 95th percentile of :attr:`moves` / 2.45.
    p95_xy : float
        95th percentile [m] of the nodes' moves once the common shift is removed.
    shift : ndarray of shape (2,)
        The move [m] (map frame) that all nodes share, removed before the percentile.
    moves : ndarray of shape (K,)
        Each used node's move [m] once :attr:`shift` is removed.
    nodes : int
        Nodes used (their scan constrains the position in every direction).
    skipped : int
        Nodes left out (too few beams, or a direction left unconstrained).
    """

    std_xy: float
    p95_xy: float
    shift: FloatArray
    moves: FloatArray
    nodes: int
    skipped: int

    def as_dict(self) -> dict[str, float | int]:
        """Plain numbers for the map's YAML (``symloc_slam.map_error``)."""
        return {
            "std_xy": round(float(self.std_xy), 4),
            "p95_xy": round(float(self.p95_xy), 4),
            "nodes": int(self.nodes),
        }


def estimate_map_error(
    grid: OccupancyGrid,
    scans: Sequence[LaserScan],
    poses: ArrayLike,
    *,
    config: ScanMatchConfig | None = None,
    max_std: float = 0.05,
    min_points: int = 60,
) -> MapError | None:
    """Align each scan of ``scans`` again to ``grid`` from its pose in ``poses`` (K, 3) and
    estimate the map's error from how far the scans move (module docstring).

    ``max_std`` [m]: a node whose alignment leaves a position std above it along some direction
    is skipped; ``min_points``: so is a scan with fewer returning beams. None when fewer than
    3 nodes are usable. The default ``config`` is the localizer's, in NumPy
    (``compiled=False``: the same numbers without loading numba into a mapping process).
    """
    cfg = config if config is not None else ScanMatchConfig(compiled=False)
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    if len(scans) != p.shape[0]:
        raise ValueError(f"poses: expected one per scan ({len(scans)}), got {p.shape[0]}")
    field = surface_distance_field(grid, max_dist=max(1.0, 2.0 * cfg.outlier_distance))
    moves: list[FloatArray] = []
    skipped = 0
    for scan, pose in zip(scans, p, strict=True):
        pts = scan.to_points().points
        if pts.shape[0] < min_points:
            skipped += 1
            continue
        match = match_scan_to_map(field, pts, pose, cfg)
        info_xy = np.asarray(match.information, dtype=np.float64)[:2, :2]
        weakest = float(np.linalg.eigvalsh(info_xy)[0])
        if not math.isfinite(weakest) or weakest <= 1.0 / max_std**2:
            skipped += 1
            continue
        moves.append(match.pose[:2] - pose[:2])
    if len(moves) < 3:
        logger.info("map error: %d usable nodes of %d, no estimate", len(moves), len(scans))
        return None
    d = np.asarray(moves)
    shift = np.median(d, axis=0)
    rest = np.hypot(*(d - shift).T)
    p95 = float(np.percentile(rest, 95))
    return MapError(
        std_xy=p95 / R95,
        p95_xy=p95,
        shift=shift,
        moves=rest,
        nodes=len(moves),
        skipped=skipped,
    )
