"""ROS message layouts <-> symloc types: pure Python, no rclpy, no ROS installation.

The conversions read messages only through their ROS field names, so they work on rclpy
messages, on ``rosbags`` message dataclasses and on look-alike objects. Going the other way they
return plain nested field dicts; :mod:`symloc.msgs.build` turns those into rclpy or rosbags
messages. Both the bag reader (:mod:`symloc.io.rosbag`) and the ROS 2 node (:mod:`symloc.ros`)
use this package; it imports neither.
"""

from __future__ import annotations

from symloc.msgs.build import build_rclpy, build_rosbags
from symloc.msgs.grid import grid_from_msg, grid_to_fields
from symloc.msgs.image import (
    SUPPORTED_ENCODINGS,
    compressed_image_from_msg,
    compressed_image_to_fields,
    image_from_msg,
    image_to_fields,
)
from symloc.msgs.odometry import odometry_from_msg, odometry_to_fields
from symloc.msgs.pose import (
    covariance_from_ros,
    covariance_to_ros,
    pose_array_to_fields,
    pose_from_msg,
    pose_stamped_to_fields,
    pose_with_covariance_from_msg,
    pose_with_covariance_to_fields,
)
from symloc.msgs.scan import scan_from_msg, scan_to_fields

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
