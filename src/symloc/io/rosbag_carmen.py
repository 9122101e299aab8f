"""Convert a CARMEN laser log into a ROS bag (``symloc ros carmen-to-bag``).

Each ``FLASER`` message becomes a ``/scan`` (sensor_msgs/LaserScan, frame ``laser``), an
``/odom`` (nav_msgs/Odometry, the odometry pose recorded with the scan, ``odom`` ->
``base_link``) and a ``/ground_truth`` (nav_msgs/Odometry in the ``map`` frame: the log's
corrected laser pose, the reference trajectory of the "corrected" Radish logs). So real logs
can be replayed through the same bag path a ROS user's recordings take.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

from symloc.errors import DataFormatError
from symloc.io.carmen import read_carmen
from symloc.io.rosbag import BagFormat, BagWriter
from symloc.odometry import OdometryReading

__all__ = ["carmen_to_bag"]


def carmen_to_bag(
    log: str | Path, out: str | Path, *, fmt: BagFormat = "ros2", range_max: float = 50.0
) -> Counter[str]:
    """Write the scans, odometry and corrected poses of CARMEN ``log`` as a bag at ``out``.

    Returns the number of messages written per topic.

    Raises
    ------
    DataFormatError
        The log is malformed (from :func:`symloc.io.carmen.read_carmen`), holds no ``FLASER``
        scan (nothing is written), or ``out`` exists.
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
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with BagWriter(out, fmt) as bag:
        for s in data.scans:
            bag.write_odometry(OdometryReading(s.odom_pose, s.stamp))
            bag.write_scan(s.scan.with_ranges(s.scan.ranges, stamp=s.stamp))
            bag.write_truth(s.laser_pose, s.stamp)
    return bag.counts
