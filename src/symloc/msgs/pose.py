"""geometry_msgs poses: Pose, PoseStamped, PoseWithCovarianceStamped, PoseArray.

A planar pose ``(3,)`` is x [m], y [m], theta [rad]; its 3x3 covariance is over (x, y, yaw),
taken from / written to the rows and columns 0, 1 and 5 of the ROS 6x6 row-major covariance
(x, y, z, roll, pitch, yaw), as nav2_amcl does.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import DataFormatError
from symloc.msgs.fields import field, finite_field, quaternion_from_yaw, yaw_from_quaternion
from symloc.msgs.header import header_fields

__all__ = [
    "COV_INDEX",
    "covariance_from_ros",
    "covariance_to_ros",
    "pose_array_to_fields",
    "pose_fields",
    "pose_from_msg",
    "pose_stamped_to_fields",
    "pose_with_covariance_from_msg",
    "pose_with_covariance_to_fields",
]

COV_INDEX = np.array([0, 1, 5])
"""Rows/columns of the ROS 6x6 covariance that hold x, y and yaw."""

FloatArray = NDArray[np.float64]


def pose_from_msg(pose: Any, where: str) -> FloatArray:
    """A geometry_msgs/Pose as ``(3,)`` x, y, yaw; NaN or a zero quaternion raises."""
    x = finite_field(pose, "position.x", where)
    y = finite_field(pose, "position.y", where)
    yaw = yaw_from_quaternion(field(pose, "orientation", where), f"{where}.orientation")
    return np.array([x, y, yaw])


def pose_fields(pose: ArrayLike) -> dict[str, Any]:
    """A geometry_msgs/Pose field dict from ``(3,)`` x, y, yaw."""
    p = np.asarray(pose, dtype=np.float64)
    return {
        "position": {"x": float(p[0]), "y": float(p[1]), "z": 0.0},
        "orientation": quaternion_from_yaw(float(p[2])),
    }


def covariance_from_ros(cov: Any, where: str) -> FloatArray:
    """The ``(3, 3)`` x, y, yaw block of a 36-element ROS covariance; must be finite."""
    try:
        c = np.asarray(cov, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as err:
        raise DataFormatError(f"{where}: expected 36 numbers") from err
    if c.size != 36:
        raise DataFormatError(f"{where}: expected 36 numbers (6x6), got {c.size}")
    if not np.all(np.isfinite(c)):
        raise DataFormatError(f"{where}: contains NaN or infinite values")
    block: FloatArray = c.reshape(6, 6)[np.ix_(COV_INDEX, COV_INDEX)]
    if np.any(np.diag(block) < 0):
        raise DataFormatError(f"{where}: negative variance on the diagonal {np.diag(block)}")
    return block


def covariance_to_ros(cov3: ArrayLike) -> FloatArray:
    """A 36-element ROS covariance holding the ``(3, 3)`` x, y, yaw block (others zero)."""
    c = np.zeros((6, 6))
    c[np.ix_(COV_INDEX, COV_INDEX)] = np.asarray(cov3, dtype=np.float64).reshape(3, 3)
    return c.reshape(36)


def pose_with_covariance_from_msg(msg: Any) -> tuple[FloatArray, FloatArray]:
    """A geometry_msgs/PoseWithCovarianceStamped as ``(pose (3,), covariance (3, 3))``."""
    where = "PoseWithCovarianceStamped"
    pose = pose_from_msg(field(msg, "pose.pose", where), f"{where}.pose.pose")
    cov = covariance_from_ros(field(msg, "pose.covariance", where), f"{where}.pose.covariance")
    return pose, cov


def pose_with_covariance_to_fields(
    pose: ArrayLike, covariance: ArrayLike, *, stamp: float, frame_id: str = "map"
) -> dict[str, Any]:
    """A geometry_msgs/PoseWithCovarianceStamped field dict."""
    return {
        "header": header_fields(stamp, frame_id),
        "pose": {"pose": pose_fields(pose), "covariance": covariance_to_ros(covariance)},
    }


def pose_stamped_to_fields(pose: ArrayLike, *, stamp: float, frame_id: str) -> dict[str, Any]:
    """A geometry_msgs/PoseStamped field dict."""
    return {"header": header_fields(stamp, frame_id), "pose": pose_fields(pose)}


def pose_array_to_fields(poses: ArrayLike, *, stamp: float, frame_id: str) -> dict[str, Any]:
    """A geometry_msgs/PoseArray field dict from ``(N, 3)`` poses."""
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    half = 0.5 * p[:, 2]
    sz, cz = np.sin(half), np.cos(half)
    return {
        "header": header_fields(stamp, frame_id),
        "poses": [
            {
                "position": {"x": float(x), "y": float(y), "z": 0.0},
                "orientation": {"x": 0.0, "y": 0.0, "z": float(s), "w": float(c)},
            }
            for x, y, s, c in zip(p[:, 0], p[:, 1], sz, cz, strict=True)
        ],
    }
