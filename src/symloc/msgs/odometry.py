"""``nav_msgs/Odometry`` <-> :class:`symloc.odometry.OdometryReading`."""

from __future__ import annotations

from typing import Any

import numpy as np

from symloc.msgs.fields import field
from symloc.msgs.header import header_fields, header_stamp
from symloc.msgs.pose import covariance_to_ros, pose_fields, pose_from_msg
from symloc.odometry import OdometryReading

__all__ = ["odometry_from_msg", "odometry_to_fields"]

_WHERE = "Odometry"


def odometry_from_msg(msg: Any) -> OdometryReading:
    """The pose of a nav_msgs/Odometry (``header.frame_id`` <- ``child_frame_id``) and its stamp.

    Raises
    ------
    DataFormatError
        A field is missing, NaN, or the orientation is a zero quaternion.
    """
    pose = pose_from_msg(field(msg, "pose.pose", _WHERE), f"{_WHERE}.pose.pose")
    return OdometryReading(pose, header_stamp(msg, _WHERE))


def odometry_to_fields(
    reading: OdometryReading,
    *,
    frame_id: str = "odom",
    child_frame_id: str = "base_link",
    velocity: tuple[float, float] | None = None,
    pose_variance: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> dict[str, Any]:
    """A nav_msgs/Odometry field dict; ``velocity`` is (v [m/s], omega [rad/s]) if known."""
    twist = np.zeros(6)
    if velocity is not None:
        twist[0], twist[5] = velocity
    return {
        "header": header_fields(reading.stamp, frame_id),
        "child_frame_id": child_frame_id,
        "pose": {
            "pose": pose_fields(reading.pose),
            "covariance": covariance_to_ros(np.diag(pose_variance)),
        },
        "twist": {
            "twist": {
                "linear": {"x": float(twist[0]), "y": 0.0, "z": 0.0},
                "angular": {"x": 0.0, "y": 0.0, "z": float(twist[5])},
            },
            "covariance": np.zeros(36),
        },
    }
