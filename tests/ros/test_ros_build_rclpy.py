"""The conversions build real rclpy messages (skipped when the ROS extra is not installed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import DataFormatError
from symloc.grid import OccupancyGrid
from symloc.msgs import (
    build_rclpy,
    grid_from_msg,
    grid_to_fields,
    image_from_msg,
    image_to_fields,
    pose_array_to_fields,
    scan_from_msg,
    scan_to_fields,
)
from symloc.scan import LaserScan

sensor_msgs = pytest.importorskip(
    "sensor_msgs.msg",
    reason="rclpy message packages absent: pip install '.[ros]' in symloc's checkout",
)
geometry_msgs = pytest.importorskip(
    "geometry_msgs.msg", reason="pip install '.[ros]' in symloc's checkout"
)
nav_msgs = pytest.importorskip("nav_msgs.msg", reason="pip install '.[ros]' in symloc's checkout")


def test_rclpy_scan_round_trip() -> None:
    scan = LaserScan(-math.pi, math.pi / 180, 0.1, 10.0, np.linspace(1, 3, 360), stamp=7.25)
    msg = build_rclpy(sensor_msgs.LaserScan, scan_to_fields(scan))
    assert isinstance(msg, sensor_msgs.LaserScan)
    assert msg.header.stamp.sec == 7
    back = scan_from_msg(msg)
    np.testing.assert_allclose(back.ranges, scan.ranges.astype(np.float32))


def test_rclpy_grid_image_posearray() -> None:
    grid = OccupancyGrid(np.full((3, 4), 100, np.int8), 0.05, np.array([1.0, 2.0, 0.0]))
    g = build_rclpy(nav_msgs.OccupancyGrid, grid_to_fields(grid, stamp=1.0))
    np.testing.assert_array_equal(grid_from_msg(g).data, grid.data)
    img = np.random.default_rng(0).integers(0, 255, (8, 9, 3), dtype=np.uint8)
    im = build_rclpy(sensor_msgs.Image, image_to_fields(img, stamp=1.0))
    np.testing.assert_array_equal(image_from_msg(im), img)
    pa = build_rclpy(
        geometry_msgs.PoseArray, pose_array_to_fields(np.zeros((5, 3)), stamp=0, frame_id="map")
    )
    assert len(pa.poses) == 5
    assert pa.poses[0].orientation.w == pytest.approx(1.0)


def test_rclpy_unknown_field() -> None:
    with pytest.raises(DataFormatError, match=r"LaserScan\.nope: no such field"):
        build_rclpy(sensor_msgs.LaserScan, {"nope": 1})
