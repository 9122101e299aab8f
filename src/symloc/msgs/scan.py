"""``sensor_msgs/LaserScan`` <-> :class:`symloc.scan.LaserScan`."""

from __future__ import annotations

from typing import Any

import numpy as np

from symloc.errors import DataFormatError
from symloc.msgs.fields import finite_field, numeric_array
from symloc.msgs.header import header_fields, header_frame, header_stamp
from symloc.scan import LaserScan

__all__ = ["scan_from_msg", "scan_to_fields"]

_WHERE = "LaserScan"


def scan_from_msg(msg: Any, *, expected_beams: int | None = None) -> LaserScan:
    """Convert a sensor_msgs/LaserScan (rclpy, rosbags or look-alike) to a :class:`LaserScan`.

    A clockwise scan (``angle_increment < 0``) is reversed so that the result's increment is
    positive, as :class:`LaserScan` requires. ``angle_max`` of the message is not trusted
    (drivers disagree on it); the beam angles follow ``angle_min + i * angle_increment``.

    Parameters
    ----------
    msg : object
        Has the fields of sensor_msgs/LaserScan.
    expected_beams : int, optional
        If given, a scan with another number of ranges is rejected.

    Raises
    ------
    DataFormatError
        A field is missing or malformed; the message names it.
    """
    angle_min = finite_field(msg, "angle_min", _WHERE)
    inc = finite_field(msg, "angle_increment", _WHERE)
    ranges = numeric_array(getattr(msg, "ranges", None), f"{_WHERE}.ranges")
    if ranges.size == 0:
        raise DataFormatError(f"{_WHERE}.ranges: expected at least one reading, got none")
    if expected_beams is not None and ranges.size != expected_beams:
        raise DataFormatError(
            f"{_WHERE}.ranges: expected {expected_beams} readings as in earlier scans,"
            f" got {ranges.size}"
        )
    raw_int = getattr(msg, "intensities", None)
    intens = None if raw_int is None else numeric_array(raw_int, f"{_WHERE}.intensities")
    if intens is not None and intens.size not in (0, ranges.size):
        raise DataFormatError(
            f"{_WHERE}.intensities: expected 0 or {ranges.size} values, got {intens.size}"
        )
    if inc < 0.0:
        angle_min = angle_min + inc * (ranges.size - 1)
        inc = -inc
        ranges = ranges[::-1].copy()
        if intens is not None and intens.size:
            intens = intens[::-1].copy()
    return LaserScan(
        angle_min=angle_min,
        angle_increment=inc,
        range_min=finite_field(msg, "range_min", _WHERE),
        range_max=finite_field(msg, "range_max", _WHERE),
        ranges=ranges,
        intensities=intens if intens is not None and intens.size else None,
        stamp=header_stamp(msg, _WHERE),
        time_increment=finite_field(msg, "time_increment", _WHERE),
        scan_time=finite_field(msg, "scan_time", _WHERE),
        frame_id=header_frame(msg, _WHERE),
    )


def scan_to_fields(scan: LaserScan, *, frame_id: str | None = None) -> dict[str, Any]:
    """A sensor_msgs/LaserScan field dict (ranges as float32, as on the wire)."""
    return {
        "header": header_fields(scan.stamp, scan.frame_id if frame_id is None else frame_id),
        "angle_min": scan.angle_min,
        "angle_max": scan.angle_max,
        "angle_increment": scan.angle_increment,
        "time_increment": scan.time_increment,
        "scan_time": scan.scan_time,
        "range_min": scan.range_min,
        "range_max": scan.range_max,
        "ranges": np.asarray(scan.ranges, dtype=np.float32),
        "intensities": (
            np.zeros(0, np.float32)
            if scan.intensities is None
            else np.asarray(scan.intensities, dtype=np.float32)
        ),
    }
