"""Convert a CARMEN laser log into a ROS bag (``symloc ros carmen-to-bag``).

Each ``FLASER`` message becomes a ``/scan`` (sensor_msgs/LaserScan, frame ``laser``), an
``/odom`` (nav_msgs/Odometry, the odometry pose recorded with the scan, or one given per scan,
``odom`` -> ``base_link``) and a ``/ground_truth`` (nav_msgs/Odometry in the ``map`` frame: the log's
corrected laser pose, the reference trajectory of the "corrected" Radish logs). Before the first
scan it writes an ``/initialpose`` (geometry_msgs/PoseWithCovarianceStamped, ``map`` frame) at
the first corrected pose with the covariance :data:`START_COVARIANCE` (5 cm, 3 deg std), as
``symloc experiment amcl-carmen`` starts symloc's localizer: a map built from the same log (``symloc
map build --carmen``, ``symloc replay --build-map``) starts at that pose, so the replay tracks
from there, as ``symloc experiment amcl-carmen`` does. So real logs can be replayed through the
same bag path a ROS user's recordings take.

The bag keeps what the logs hold: a scan every 0.05-40 s where the robot moved (the corrected
logs keep only those), pauses of up to tens of seconds, and the odometry only at the scans (the
``ODOM`` lines of these logs carry stamps from another clock and are not written). Every
message's log time is its stamp. A log without usable stamps
(:func:`symloc.io.carmen.stamps_usable`: orebro's are all 0, csail's truncated to the same
value) is given time by its motion (:func:`motion_stamps`), and said so: with one stamp for
every scan, the odometry would move at infinite speed between them and a replay would reject
it. A scan stamped at or before the scan above it in the log (intel's four clock glitches, 0.05
to 0.86 s back) is stamped after it by its motion (:func:`ordered_stamps`), and said so: the
log's order is the order the robot took them (its corrected poses turn smoothly in that
order), and a bag consumer takes a scan stamped before the previous one for an outlier
(``symloc replay --build-map`` would map without it, where ``symloc map build --carmen``
maps with it: issue 28 wants one input on both paths).
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError, DataFormatError
from symloc.io.carmen import read_carmen, stamps_usable
from symloc.io.rosbag import BagFormat, BagWriter
from symloc.odometry import OdometryReading

#: nav2_amcl's default initial covariance: x, y variance [m^2] and yaw variance [rad^2].
INITIAL_COVARIANCE = np.diag([0.5**2, 0.5**2, (math.pi / 12.0) ** 2])
#: The covariance of a start at a log's first corrected pose (5 cm, 3 deg std; x, y variance
#: [m^2], yaw variance [rad^2]): what ``symloc experiment amcl-carmen`` gives symloc's localizer
#: and carmen-to-bag writes on ``/initialpose``. The corrected pose is the reference itself, not
#: an operator's click; from nav2's default (0.5 m, 15 deg) AMCL's first estimate on fhw was
#: 0.56 m off, the claim gate gave the pose up and after 60 scans took a scan that fits the
#: map poorly (17-28 % of beams) for a kidnapping: AMCL reset to global, 26 m mean error.
START_COVARIANCE = np.diag([0.05**2, 0.05**2, math.radians(3.0) ** 2])

#: Speed [m/s] and turn rate [rad/s] at which a log without usable stamps is given time.
NOMINAL_SPEED = 0.5
NOMINAL_TURN_RATE = math.pi / 2
#: The shortest interval [s] between two scans of such a log.
MIN_INTERVAL = 0.1

__all__ = [
    "INITIAL_COVARIANCE",
    "MIN_INTERVAL",
    "NOMINAL_SPEED",
    "NOMINAL_TURN_RATE",
    "START_COVARIANCE",
    "carmen_to_bag",
    "motion_stamps",
    "ordered_stamps",
]

FloatArray = NDArray[np.float64]
logger = logging.getLogger(__name__)


def carmen_to_bag(
    log: str | Path,
    out: str | Path,
    *,
    fmt: BagFormat = "ros2",
    range_max: float = 50.0,
    initial_pose: bool = True,
    odometry: ArrayLike | None = None,
    notes: list[str] | None = None,
    initial_covariance: ArrayLike = START_COVARIANCE,
) -> Counter[str]:
    """Write the scans, odometry and corrected poses of CARMEN ``log`` as a bag at ``out``;
    with ``initial_pose`` also the first corrected pose on ``/initialpose``, with
    ``initial_covariance`` (3, 3) [m^2, rad^2] (:data:`INITIAL_COVARIANCE` for nav2's default).

    ``odometry`` (N, 3) x [m], y [m], theta [rad], one pose per scan: written on ``/odom``
    instead of the log's own odometry (the corrected logs' odometry is their corrected poses:
    a replay of it tracks with perfect odometry; ``symloc ros carmen-to-bag --odom-alpha``
    passes the noisy odometry of ``symloc experiment amcl-carmen`` here).

    ``notes``, a list, receives a line for what the bag does not take from the log as it is
    (stamps given by the motion when the log has none); without it the line is logged as a
    warning.

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
    stamps = data.stamps
    if not stamps_usable(stamps):
        stamps = motion_stamps(data.laser_poses, max(float(stamps[0]), 0.0))
        note = (
            f"{log}: the scans' stamps do not measure time (fewer than 90 % increase); the bag"
            f" stamps them by the motion at {NOMINAL_SPEED:g} m/s and"
            f" {math.degrees(NOMINAL_TURN_RATE):g} deg/s, at least {MIN_INTERVAL:g} s apart"
            f" ({stamps[-1] - stamps[0]:.1f} s in all)"
        )
        if notes is None:
            logger.warning(note)
        else:
            notes.append(note)
    stamps, moved = ordered_stamps(stamps, data.laser_poses)
    if moved:
        note = (
            f"{log}: {moved} scan(s) stamped at or before the scan above them in the log (clock"
            " glitches; the log's order is the robot's) are stamped after it by the motion"
            f" between them ({NOMINAL_SPEED:g} m/s, {math.degrees(NOMINAL_TURN_RATE):g} deg/s,"
            f" at least {MIN_INTERVAL:g} s)"
        )
        if notes is None:
            logger.warning(note)
        else:
            notes.append(note)
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with BagWriter(out, fmt) as bag:
        if initial_pose:
            first = data.scans[0]
            bag.write_initialpose(first.laser_pose, initial_covariance, float(stamps[0]))
        for s, pose, t in zip(data.scans, odom, stamps.tolist(), strict=True):
            bag.write_odometry(OdometryReading(pose, t))
            bag.write_scan(s.scan.with_ranges(s.scan.ranges, stamp=t))
            bag.write_truth(s.laser_pose, t)
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


def _motion_intervals(p: FloatArray) -> FloatArray:
    """(N - 1,) [s]: the time a robot driving at :data:`NOMINAL_SPEED` and turning at
    :data:`NOMINAL_TURN_RATE` takes between consecutive poses of ``p`` (N, 3) (whichever is
    longer, and at least :data:`MIN_INTERVAL`)."""
    step = np.hypot(*np.diff(p[:, :2], axis=0).T) / NOMINAL_SPEED
    turn = np.abs(np.angle(np.exp(1j * np.diff(p[:, 2])))) / NOMINAL_TURN_RATE
    return np.asarray(np.maximum(np.maximum(step, turn), MIN_INTERVAL), dtype=np.float64)


def motion_stamps(poses: ArrayLike, start: float = 0.0) -> FloatArray:
    """Stamps [s] (N,) for scans taken at ``poses`` (N, 3) x [m], y [m], theta [rad] by a robot
    that drives at :data:`NOMINAL_SPEED` and turns at :data:`NOMINAL_TURN_RATE` (whichever
    takes longer between two scans, and at least :data:`MIN_INTERVAL`), from ``start`` [s]."""
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    if p.shape[0] == 0:
        return np.zeros(0)
    dt = _motion_intervals(p)
    return np.asarray(start + np.concatenate([[0.0], np.cumsum(dt)]), dtype=np.float64)


def ordered_stamps(stamps: ArrayLike, poses: ArrayLike) -> tuple[FloatArray, int]:
    """``stamps`` (N,) [s] with each stamp at or before the previous (as written here) moved
    after it by the motion between their ``poses`` (N, 3) (:func:`motion_stamps`' interval),
    and how many were moved. Stamps that increase are kept as they are; a scan written just
    after a moved one keeps its own stamp when that is later.

    Examples
    --------
    >>> t, n = ordered_stamps([0.0, 1.0, 0.9, 2.0], [[0, 0, 0], [1, 0, 0], [1.1, 0, 0], [2, 0, 0]])
    >>> [round(float(v), 6) for v in t], n
    ([0.0, 1.0, 1.2, 2.0], 1)
    """
    t = np.array(stamps, dtype=np.float64).reshape(-1)
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    if p.shape[0] != t.size:
        raise ConfigurationError(
            f"poses: expected {t.size} poses (one per stamp), got {p.shape[0]}"
        )
    if t.size < 2 or bool(np.all(np.diff(t) > 0)):
        return t, 0
    dt = _motion_intervals(p)
    moved = 0
    for i in range(1, t.size):
        if t[i] <= t[i - 1]:
            t[i] = t[i - 1] + dt[i - 1]
            moved += 1
    return t, moved
