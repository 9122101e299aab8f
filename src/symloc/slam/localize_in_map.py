"""Poses of more scans in a map already built: odometry carried, each scan aligned to the map.

After a mapping run, a robot may go on driving to record more (the mapping trip's stops to look
around, :func:`symloc.bench.exploration.coverage_stops`, whose camera keyframes need poses in
the map). Feeding those scans to SLAM as well is not free: in the middle of a large round room
the laser observes no heading and ranges may not reach every wall, and minutes of turning on the
spot there let SLAM drift by a metre and smear the walls it already drew. The map the lap drew
is kept instead, and each further scan is placed in it: the previous pose carried by the
odometry's increment (:func:`symloc.geometry.relative`), then aligned to the map's surface
distance field by the claim gate's matcher (:func:`symloc.mcl.scan_to_map.match_scan_to_map`)
with the carried pose as its prior. A scan whose beams fit the map poorly (``min_fit``) keeps
the carried pose. Where the laser does not observe a direction (the heading in a round room),
the pose follows the odometry there, as SLAM's would.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError
from symloc.geometry import compose, relative
from symloc.grid.fields import surface_distance_field
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.mcl.beams import select_beams
from symloc.mcl.scan_to_map import ScanMatchConfig, match_scan_to_map, scan_points
from symloc.scan import LaserScan

__all__ = ["localize_in_map"]

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

#: Odometry's error growth for the matcher's prior: std [m] per metre driven and [rad] per
#: radian turned, plus a floor [m], [rad] per scan (a few times a calibrated drive's).
_PER_METRE, _PER_RADIAN = 0.05, 0.05
_FLOOR_XY, _FLOOR_THETA = 0.01, np.radians(0.5)


def localize_in_map(
    grid: OccupancyGrid,
    scans: Sequence[LaserScan],
    odometry: ArrayLike,
    start: ArrayLike,
    *,
    laser_pose: ArrayLike = (0.0, 0.0, 0.0),
    min_fit: float = 0.5,
    max_beams: int = 180,
    config: ScanMatchConfig | None = None,
) -> FloatArray:
    """Map poses ``(N, 3)`` [m, m, rad] of ``scans`` (N) in ``grid``.

    ``odometry`` ``(N + 1, 3)``: the odometry pose at ``start`` (the map pose ``(3,)`` of the
    robot just before the first scan, e.g. SLAM's last pose) and then at each scan.
    ``laser_pose`` the laser in the robot frame; ``min_fit`` the share of a scan's beams that
    must end within the matcher's inlier distance of an obstacle for its alignment to be taken;
    ``max_beams`` beams per scan at most.
    """
    odo = np.asarray(odometry, dtype=np.float64).reshape(-1, 3)
    if odo.shape[0] != len(scans) + 1:
        raise ConfigurationError(
            f"odometry: expected {len(scans) + 1} poses (the start's and one per scan), "
            f"got {odo.shape[0]}"
        )
    pose = np.asarray(start, dtype=np.float64).reshape(3)
    if not np.all(np.isfinite(pose)):
        raise ConfigurationError(f"start: expected a finite pose, got {pose}")
    if not 0.0 <= min_fit <= 1.0:
        raise ConfigurationError(f"min_fit: expected a share in [0, 1], got {min_fit}")
    out = np.empty((len(scans), 3))
    if not scans:
        return out
    field = surface_distance_field(grid)
    lp = np.asarray(laser_pose, dtype=np.float64).reshape(3)
    kept = 0
    for i, scan in enumerate(scans):
        step = relative(odo[i], odo[i + 1])
        pose = np.asarray(compose(pose, step), dtype=np.float64)
        moved, turned = float(np.hypot(step[0], step[1])), abs(float(step[2]))
        sxy = _FLOOR_XY + _PER_METRE * moved
        sth = _FLOOR_THETA + _PER_RADIAN * turned
        beams = select_beams(scan, max_beams)
        pts = scan_points(beams.ranges[beams.hit], beams.angles[beams.hit], lp)
        if pts.shape[0] >= 10:
            cov = np.diag([sxy * sxy, sxy * sxy, sth * sth])
            match = match_scan_to_map(field, pts, pose, config, prior=(pose, cov))
            if match.inlier_fraction >= min_fit:
                pose = np.asarray(match.pose, dtype=np.float64)
                kept += 1
        out[i] = pose
    log.info("localized %d scans in the map; %d aligned, the rest carried", len(scans), kept)
    return out
