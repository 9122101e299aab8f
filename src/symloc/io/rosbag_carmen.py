"""Convert a CARMEN laser log into a ROS bag (``symloc ros carmen-to-bag``).

Each ``FLASER`` message becomes a ``/scan`` (sensor_msgs/LaserScan, frame ``laser``), an
``/odom`` (nav_msgs/Odometry, the odometry pose recorded with the scan, or one given per scan,
``odom`` -> ``base_link``) and a ``/ground_truth`` (nav_msgs/Odometry in the ``map`` frame: the log's
corrected laser pose, the reference trajectory of the "corrected" Radish logs). Before the first
scan it writes an ``/initialpose`` (geometry_msgs/PoseWithCovarianceStamped, ``map`` frame) at
the first corrected pose with nav2_amcl's default initial covariance (0.5 m std, 15 deg std),
as an operator gives it with RViz's 2D Pose Estimate: a map built from the same log (``symloc
map build --carmen``, ``symloc replay --build-map``) starts at that pose, so the replay tracks
from there, as ``symloc experiment amcl-carmen`` does. So real logs can be replayed through the
same bag path a ROS user's recordings take.

The bag keeps what the logs hold: a scan every 0.05-40 s where the robot moved (the corrected
logs keep only those), pauses of up to tens of seconds, the odometry only at the scans (the
``ODOM`` lines of these logs carry stamps from another clock and are not written), and stamps
that go backwards now and then (intel). Every message's log time is its stamp.
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError, DataFormatError
from symloc.io.carmen import read_carmen
from symloc.io.rosbag import BagFormat, BagWriter
from symloc.odometry import OdometryReading

#: nav2_amcl's default initial covariance: x, y variance [m^2] and yaw variance [rad^2].
INITIAL_COVARIANCE = np.diag([0.5**2, 0.5**2, (math.pi / 12.0) ** 2])

__all__ = ["INITIAL_COVARIANCE", "carmen_to_bag"]

FloatArray = NDArray[np.float64]


def carmen_to_bag(
    log: str | Path,
    out: str | Path,
    *,
    fmt: BagFormat = "ros2",
    range_max: float = 50.0,
    initial_pose: bool = True,
    odometry: ArrayLike | None = None,
) -> Counter[str]:
    """Write the scans, odometry and corrected poses of CARMEN ``log`` as a bag at ``out``;
    with ``initial_pose`` also the first corrected pose on ``/initialpose``.

    ``odometry`` (N, 3) x [m], y [m], theta [rad], one pose per scan: written on ``/odom``
    instead of the log's own odometry (the corrected logs' odometry is their corrected poses:
    a replay of it tracks with perfect odometry; ``symloc ros carmen-to-bag --odom-alpha``
    passes the noisy odometry of ``symloc experiment amcl-carmen`` here).

    Returns the number of messages written per topic.

    Raises
    ------
    DataFormatError
        The log is malformed (from :func:`symloc.io.carmen.read_carmen`), holds no ``FLASER``
        scan (nothing is written), or ``out`` exists.
    ConfigurationError
        ``odometry`` is not one finite pose per scan of the log.
    """
    data = read_carmen(log, range_max=range_max)
    if not data.scans:
        seen = (
            ", ".join(
                (k if k.isascii() and k.isprintable() and len(k) <= 20 else ascii(k[:12]) + "...")
                + f" x{n}"
                for k, n in data.skipped.most_common(3)
            )
            or "nothing"
        )
        raise DataFormatError(
            f"{log}: no FLASER scan in it (read {len(data.odometry)} ODOM, skipped {seen});"
            " not a CARMEN laser log? No bag written"
        )
    odom = _odometry(odometry, data.odom_poses, log)
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with BagWriter(out, fmt) as bag:
        if initial_pose:
            first = data.scans[0]
            bag.write_initialpose(first.laser_pose, INITIAL_COVARIANCE, first.stamp)
        for s, pose in zip(data.scans, odom, strict=True):
            bag.write_odometry(OdometryReading(pose, s.stamp))
            bag.write_scan(s.scan.with_ranges(s.scan.ranges, stamp=s.stamp))
            bag.write_truth(s.laser_pose, s.stamp)
    return bag.counts


def _odometry(given: ArrayLike | None, own: FloatArray, log: str | Path) -> FloatArray:
    """The odometry poses (N, 3) to write: ``given`` checked against the log's N scans, or the
    log's ``own``."""
    if given is None:
        return own
    try:
        odom = np.asarray(given, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ConfigurationError(f"odometry: expected (N, 3) numbers, got {given!r}") from err
    if odom.shape != own.shape or not np.all(np.isfinite(odom)):
        raise ConfigurationError(
            f"odometry: expected {own.shape[0]} finite poses x, y, theta (one per scan of {log}),"
            f" got an array of shape {odom.shape}"
        )
    return odom
