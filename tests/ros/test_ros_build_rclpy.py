"""The conversions build real rclpy messages (skipped when the ROS extra is not installed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import DataFormatError
from symloc.grid import OccupancyGrid
from symloc.ros import (
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
    "sensor_msgs.msg", reason="rclpy message packages absent: pip install symloc[ros]"
)
geometry_msgs = pytest.importorskip("geometry_msgs.msg", reason="pip install symloc[ros]")
nav_msgs = pytest.importorskip("nav_msgs.msg", reason="pip install symloc[ros]")


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


def test_node_loads_map_yaml_and_survives_a_crashing_localizer(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import os
    import random
    import time

    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor

    from symloc.grid.map_io import save_map
    from symloc.odometry import OdometryReading
    from symloc.ros import odometry_to_fields
    from symloc.ros.node import SymlocNode
    from symloc.ros.params import NodeParams

    diagnostic_msgs = pytest.importorskip("diagnostic_msgs.msg", reason="pip install symloc[ros]")
    grid = OccupancyGrid(np.zeros((20, 20), np.int8), 0.1)
    save_map(grid, tmp_path / "m.yaml")

    class Crashing:
        def update(self, odom, scan, image=None):  # type: ignore[no-untyped-def]
            raise RuntimeError("boom")

    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    ctx = Context()
    rclpy.init(context=ctx, domain_id=random.randint(1, 100))
    params = NodeParams(map_yaml=str(tmp_path / "m.yaml"), sensor_qos="reliable")
    node = SymlocNode(params, context=ctx, factory=lambda g, p: Crashing())
    drv = rclpy.create_node("drv", context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node.node)
    ex.add_node(drv)
    try:
        assert node.core.grid is not None
        assert node.core.grid.width == 20
        statuses: list[object] = []
        drv.create_subscription(
            diagnostic_msgs.DiagnosticArray, "symloc/status", statuses.append, 10
        )
        po = drv.create_publisher(nav_msgs.Odometry, "odom", 10)
        ps = drv.create_publisher(sensor_msgs.LaserScan, "scan", 10)
        scan = LaserScan(-math.pi, math.pi / 180, 0.1, 10.0, np.full(360, 2.0), stamp=1.0)
        end = time.monotonic() + 10
        rejected = "scan: rejected by the localizer"
        while (node.core.dropped[rejected] < 2 or len(statuses) < 2) and time.monotonic() < end:
            po.publish(
                build_rclpy(
                    nav_msgs.Odometry, odometry_to_fields(OdometryReading(np.zeros(3), 1.0))
                )
            )
            ps.publish(build_rclpy(sensor_msgs.LaserScan, scan_to_fields(scan)))
            ex.spin_once(timeout_sec=0.1)
        assert node.core.dropped[rejected] >= 2  # counted, the node is still spinning
        # a status for every scan, saying the scan was not used and why
        values = {kv.key: kv.value for kv in statuses[-1].status[0].values}
        assert values["scan"] == "dropped"
        assert "RuntimeError: boom" in values["reason"]
        assert int(values["dropped"]) >= 2
    finally:
        ex.shutdown()
        node.destroy()
        drv.destroy_node()
        rclpy.shutdown(context=ctx)
