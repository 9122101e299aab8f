"""ROS interop: conversions between ROS messages and symloc types, and the ROS 2 node.

The conversions (this package's top level) are pure Python: they read messages only through
their ROS field names, so they work on rclpy messages, on ``rosbags`` message dataclasses and
on look-alike objects, and they never import rclpy. They return plain field dicts when going
the other way; :mod:`symloc.ros.build` turns those into rclpy or rosbags messages. Only
:mod:`symloc.ros.node` imports rclpy (install with ``pip install symloc[ros]``).
"""

from __future__ import annotations

from symloc.ros.build import build_rclpy, build_rosbags
from symloc.ros.grid_msg import grid_from_msg, grid_to_fields
from symloc.ros.image_msg import (
    SUPPORTED_ENCODINGS,
    compressed_image_from_msg,
    compressed_image_to_fields,
    image_from_msg,
    image_to_fields,
)
from symloc.ros.odometry_msg import odometry_from_msg, odometry_to_fields
from symloc.ros.pose_msg import (
    covariance_from_ros,
    covariance_to_ros,
    pose_array_to_fields,
    pose_from_msg,
    pose_stamped_to_fields,
    pose_with_covariance_from_msg,
    pose_with_covariance_to_fields,
)
from symloc.ros.scan_msg import scan_from_msg, scan_to_fields

__all__ = [
    "SUPPORTED_ENCODINGS",
    "build_rclpy",
    "build_rosbags",
    "compressed_image_from_msg",
    "compressed_image_to_fields",
    "covariance_from_ros",
    "covariance_to_ros",
    "grid_from_msg",
    "grid_to_fields",
    "image_from_msg",
    "image_to_fields",
    "odometry_from_msg",
    "odometry_to_fields",
    "pose_array_to_fields",
    "pose_from_msg",
    "pose_stamped_to_fields",
    "pose_with_covariance_from_msg",
    "pose_with_covariance_to_fields",
    "scan_from_msg",
    "scan_to_fields",
]
