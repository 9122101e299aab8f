"""The symloc node over real DDS on loopback: a simulated kidnapped-robot run and bad input.

Starts ``symloc ros node --autostart`` (odometry from the topic) as its own process on a random
ROS_DOMAIN_ID with discovery limited to this host (its scan topic remapped with
``--ros-args -r scan:=front/scan``), plays the simulator into it over topics (map, odom, scan, camera), carries out the
node's requests (read from ``symloc/status``) in the simulator, and checks that ``amcl_pose``
ends within 0.1 m and 5 degrees of the truth. Then it sends a burst of malformed messages and
checks that the node counts them, stays up and keeps localizing.
"""

from __future__ import annotations

import math
import os
import random
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip(
    "rclpy", reason="rclpy absent: pip install '.[ros]' in symloc's checkout to run the ROS tests"
)
pytest.importorskip("diagnostic_msgs.msg", reason="ROS message packages absent: symloc[ros]")

from ros_processes import stop_node

from symloc.bench.sim_record import drive_command, prepare_session
from symloc.grid import OccupancyGrid
from symloc.localizer import Status
from symloc.localizer.centering import CenteringConfig
from symloc.msgs import (
    build_rclpy,
    grid_to_fields,
    image_to_fields,
    odometry_to_fields,
    pose_with_covariance_to_fields,
    scan_to_fields,
)
from symloc.odometry import OdometryReading
from symloc.ros.requests import NodeStatus, status_from_msg

pytestmark = pytest.mark.slow

STEP_TIMEOUT = 20.0  # s to wait for the node's answer to one scan (a loaded CI machine)


class Driver:
    """The simulator side: publishes sensors, waits for the node's status after each scan."""

    def __init__(self, domain_id: int) -> None:
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
        from nav_msgs.msg import OccupancyGrid as GridMsg
        from nav_msgs.msg import Odometry
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import Image, LaserScan
        from std_msgs.msg import Header

        self.types = {
            "map": GridMsg,
            "odom": Odometry,
            "scan": LaserScan,
            "image": Image,
            "initialpose": PoseWithCovarianceStamped,
        }
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=domain_id)
        self.node = rclpy.create_node("symloc_test_driver", context=self.ctx)
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        n = self.node
        self.pub = {
            "map": n.create_publisher(GridMsg, "map", latched),
            "odom": n.create_publisher(Odometry, "odom", 50),
            "scan": n.create_publisher(LaserScan, "front/scan", 50),  # remapped for the node
            "image": n.create_publisher(Image, "camera/image_raw", 10),
            "initialpose": n.create_publisher(PoseWithCovarianceStamped, "initialpose", 10),
        }
        self.statuses: list[NodeStatus] = []
        self.amcl_poses: list[Any] = []
        self.goals: list[Any] = []
        self.captures: list[Any] = []
        n.create_subscription(
            DiagnosticArray, "symloc/status", lambda m: self.statuses.append(status_from_msg(m)), 50
        )
        n.create_subscription(
            PoseWithCovarianceStamped, "amcl_pose", self.amcl_poses.append, latched
        )
        # requests to move the robot are opt-in (publish_goals), on symloc's own topic
        n.create_subscription(PoseStamped, "symloc/goal", self.goals.append, 50)
        self.nav2_goals: list[Any] = []
        n.create_subscription(PoseStamped, "goal_pose", self.nav2_goals.append, 50)
        n.create_subscription(Header, "symloc/capture_request", self.captures.append, 50)

    def send(self, key: str, fields: dict[str, Any]) -> None:
        self.pub[key].publish(build_rclpy(self.types[key], fields))

    def spin_until(self, cond: Any, timeout: float) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if cond():
                return True
            self.ex.spin_once(timeout_sec=0.02)
        return bool(cond())

    def answer(self, stamp: float, since: int, timeout: float = STEP_TIMEOUT) -> NodeStatus | None:
        """The first status after index ``since`` that answers the scan stamped ``stamp``."""

        def new() -> list[NodeStatus]:
            return [s for s in self.statuses[since:] if abs(s.stamp - stamp) < 1e-6]

        if not self.spin_until(lambda: bool(new()), timeout):
            return None
        return new()[0]

    def close(self) -> None:
        import rclpy

        self.ex.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.ctx)


@pytest.fixture
def node_process(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Any:
    """The simulated session and the node running in its own process."""
    sim = prepare_session(
        tmp_path / "assets",
        room="square",
        seed=21,
        sensor_qos="reliable",
        map_yaml="",
        camera_frame_id="camera",
        laser_frame_id="laser",
        odom_source="topic",
        laser_pose_source="parameters",
    )
    domain = random.randint(1, 100)
    env = dict(os.environ)
    env.update(
        ROS_DOMAIN_ID=str(domain),
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        PYTHONUNBUFFERED="1",
    )
    env.pop("ROS_LOCALHOST_ONLY", None)
    log = (tmp_path / "node.log").open("w")
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "symloc.cli.main",
            "ros",
            "node",
            "--params",
            str(sim.params_path),
            "--autostart",
            "--ros-args",
            "-r",
            "scan:=front/scan",
            "-p",
            "publish_goals:=true",
        ],
        env=env,
        stdout=log,
        stderr=subprocess.STDOUT,
    )
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    monkeypatch.delenv("ROS_LOCALHOST_ONLY", raising=False)
    driver = Driver(domain)
    try:
        yield sim, driver, proc, tmp_path / "node.log"
    finally:
        driver.close()
        stop_node(proc)
        log.close()


def _scan_and_wait(sim: Any, driver: Driver, *, retries: int = 2) -> NodeStatus:
    t = sim.time
    for _ in range(retries + 1):
        since = len(driver.statuses)
        driver.send("scan", scan_to_fields(sim.scan()))
        st = driver.answer(t, since)
        if st is not None:
            return st
    raise AssertionError(f"no status from the node for the scan at {t:.2f} s")


def test_kidnapped_run_over_dds_then_bad_input(node_process: Any) -> None:
    sim, driver, proc, log_path = node_process
    driver.send("map", grid_to_fields(sim.grid, stamp=0.0))
    driver.send("odom", odometry_to_fields(sim.odometry()))
    # the node is up when it answers a scan (discovery, the map and the localizer's set-up)
    t0 = sim.time
    up = False
    for _ in range(60):
        driver.send("odom", odometry_to_fields(sim.odometry()))
        driver.send("scan", scan_to_fields(sim.scan()))
        if driver.answer(t0, 0, timeout=1.0) is not None:
            up = True
            break
        assert proc.poll() is None, log_path.read_text()
    assert up, "the node never answered: " + log_path.read_text()

    centering = CenteringConfig()
    st = driver.statuses[-1]
    calm = 0
    images_sent = 0
    seen = set()
    while sim.time < 60.0:
        seen.add(st.status)
        if st.request is None and st.status in (Status.TRACKING, Status.AMBIGUOUS):
            calm += 1
            if calm >= 3:
                break
        else:
            calm = 0
        if st.request is not None and st.request.kind.value == "capture_image":
            img = sim.image()
            driver.send("image", image_to_fields(img, stamp=sim.time, frame_id="camera"))
            driver.spin_until(lambda: False, 0.3)  # let the image arrive before the next scan
            st = _scan_and_wait(sim, driver)
            images_sent += 1
            continue
        scan = sim.scan()
        v, w = drive_command(st.status, st.request, scan, centering)
        odom = sim.drive(v, w)
        driver.send("odom", odometry_to_fields(odom))
        st = _scan_and_wait(sim, driver)

    assert st.status is Status.TRACKING, f"ended {st.status}: {st.reason}"
    assert Status.GOING_TO_CENTRE in seen or Status.DECIDING in seen
    assert driver.goals, "the node never published a goal pose"
    assert not driver.nav2_goals, "a goal was sent on nav2's goal_pose"
    assert driver.captures, "the node never requested an image"
    assert 1 <= images_sent <= 4, f"{images_sent} images for one decision"
    assert driver.spin_until(lambda: bool(driver.amcl_poses), 5.0)
    truth = sim.body.pose
    msg = driver.amcl_poses[-1]
    q = msg.pose.pose.orientation
    est = np.array([msg.pose.pose.position.x, msg.pose.pose.position.y, 2 * math.atan2(q.z, q.w)])
    pos_err = float(np.hypot(*(est[:2] - truth[:2])))
    head_err = abs(math.remainder(float(est[2] - truth[2]), 2 * math.pi))
    print(
        f"DDS run: final amcl_pose error {pos_err:.4f} m, {math.degrees(head_err):.2f} deg;"
        f" sim time {sim.time:.1f} s; {len(driver.statuses)} status messages;"
        f" {images_sent} image(s) sent"
    )
    assert pos_err < 0.1
    assert head_err < math.radians(5.0)

    # ---- a burst of malformed messages
    t = sim.time
    good = scan_to_fields(sim.scan())
    bad_len = dict(good, ranges=np.asarray(good["ranges"])[:-7])
    wrong_frame = dict(good, header={"stamp": good["header"]["stamp"], "frame_id": "base_link"})
    nan_inc = dict(good, angle_increment=float("nan"))
    nan_odom = odometry_to_fields(OdometryReading(sim.body.odom.pose, t))
    nan_odom["pose"]["pose"]["position"]["x"] = float("nan")
    wrong_odom = odometry_to_fields(OdometryReading(sim.body.odom.pose, t), frame_id="map")
    bad_img = image_to_fields(np.zeros((4, 4, 3), np.uint8), stamp=t, frame_id="camera")
    bad_img["encoding"] = "yuv422"
    short_img = image_to_fields(np.zeros((4, 4, 3), np.uint8), stamp=t, frame_id="camera")
    short_img["data"] = np.zeros(5, np.uint8)
    big_map = OccupancyGrid(np.zeros((50, 70), np.int8), 0.05)
    nan_pose = pose_with_covariance_to_fields([math.nan, 0.0, 0.0], np.eye(3) * 0.1, stamp=t)
    for _ in range(3):
        driver.send("scan", bad_len)
        driver.send("scan", wrong_frame)
        driver.send("scan", nan_inc)
        driver.send("odom", nan_odom)
        driver.send("odom", wrong_odom)
        driver.send("image", bad_img)
        driver.send("image", short_img)
        driver.send("initialpose", nan_pose)
    # a map in the wrong frame (a new map in the map frame is taken, as nav2_amcl takes it)
    driver.send("map", grid_to_fields(big_map, stamp=t, frame_id="odom"))
    driver.spin_until(lambda: False, 1.0)
    assert proc.poll() is None, "the node died on bad input:\n" + log_path.read_text()

    # ---- still localizing: drive a little and check the pose
    for _ in range(10):
        scan = sim.scan()
        odom = sim.drive(0.1, 0.3)
        driver.send("odom", odometry_to_fields(odom))
        st = _scan_and_wait(sim, driver)
    assert st.status is Status.TRACKING, st.reason
    assert st.pose is not None
    truth = sim.body.pose
    assert float(np.hypot(*(st.pose[:2] - truth[:2]))) < 0.1
    dropped = {
        k[len("dropped/") :]: int(v) for k, v in st.values.items() if k.startswith("dropped/")
    }
    print("dropped by the node:", dropped)
    assert dropped.get("scan: wrong length", 0) >= 3
    assert dropped.get("scan: wrong frame", 0) >= 3
    assert dropped.get("scan: malformed", 0) >= 3
    assert dropped.get("odom: malformed", 0) >= 3
    assert dropped.get("odom: wrong frame", 0) >= 3
    # no capture was pending: the images were not even decoded (NodeCore tests cover decoding)
    assert "image: malformed" not in dropped
    assert dropped.get("initialpose: malformed", 0) >= 3
    assert dropped.get("map: wrong frame", 0) >= 1
    log = log_path.read_text()
    assert "still localizing" in log
