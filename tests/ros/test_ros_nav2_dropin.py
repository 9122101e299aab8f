"""nav2's side of symloc over real DDS on loopback: the node as nav2_amcl's drop-in.

One run (a module fixture), several checks. ``symloc ros node`` starts as its own process, a
lifecycle node named ``amcl`` in state unconfigured, with nav2's own main-branch params file
(``data/nav2/main.yaml``, the ``amcl:`` block unchanged) and a second file with symloc's own
settings (visual map, vocabulary, lidar preset). Playing nav2's part, the test:

- brings it to active through ``amcl/change_state`` (configure, activate), as nav2's
  ``lifecycle_manager_localization`` does, reading ``amcl/get_state`` after each step;
- plays a simulated kidnapped run in a symmetric room: ``/tf`` (``odom -> base_footprint``),
  ``/tf_static`` (``base_footprint -> base_link -> laser``, the laser 0.2 m ahead of the
  centre and turned over, 180 degrees about y: upside down and looking backwards), ``/scan``
  in the laser's frame, ``/map`` and the camera, carrying out the node's requests;
- calls ``request_nomotion_update`` on the way, ``reinitialize_global_localization`` at the
  end (the pose is forgotten: no new ``map -> odom``) and ``set_initial_pose`` (tracking and
  transforms resume), then deactivates and cleans up.

Without ``tf2_msgs`` / ``nav2_msgs`` (not built by ``symloc ros setup`` in this environment) the run
uses the odometry topic and the ``laser_pose`` parameters instead of TF, and the checks that
need TF or ``set_initial_pose`` skip, saying why.
"""

from __future__ import annotations

import importlib
import math
import os
import random
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip(
    "rclpy", reason="rclpy absent: pip install '.[ros]' in symloc's checkout to run the ROS tests"
)
pytest.importorskip("diagnostic_msgs.msg", reason="ROS message packages absent: symloc[ros]")
pytest.importorskip(
    "std_srvs.srv", reason="std_srvs absent: pip install '.[ros]' in symloc's checkout"
)

from ros_processes import stop_node

from symloc.bench.sim_record import drive_command, prepare_session
from symloc.geometry import compose, wrap_angle
from symloc.localizer import Status
from symloc.localizer.centering import CenteringConfig
from symloc.msgs import build_rclpy, grid_to_fields, image_to_fields, scan_to_fields
from symloc.msgs.odometry import odometry_to_fields
from symloc.msgs.pose import pose_with_covariance_to_fields
from symloc.ros.requests import NodeStatus, status_from_msg
from symloc.ros.tf import transform_fields
from symloc.scan import mirror
from symloc.sim.lidar import simulate_scan

pytestmark = pytest.mark.slow

DATA = Path(__file__).parent / "data" / "nav2"
STEP_TIMEOUT = 20.0  # s to wait for the node's answer to one scan (a loaded CI machine)
#: base_link in base_footprint, and the laser in base_link: 0.2 m ahead, 0.2 m up, turned
#: over by 180 degrees about y (quaternion x, y, z, w = 0, 1, 0, 0): upside down, looking back
BASE_LINK = (0.0, 0.0, 0.1), (0.0, 0.0, 0.0, 1.0)
LASER = (0.2, 0.0, 0.2), (0.0, 1.0, 0.0, 0.0)
#: the same laser as symloc sees it once its scans are mirrored: at (0.2, 0), facing back
LASER_UPRIGHT = np.array([0.2, 0.0, math.pi])
# lifecycle_msgs: transition ids and state ids
CONFIGURE, CLEANUP, ACTIVATE, DEACTIVATE = 1, 2, 3, 4
UNCONFIGURED, INACTIVE, ACTIVE = 1, 2, 3


def _interfaces() -> str | None:
    """None when tf2_msgs, nav2_msgs and bond import, else why not.

    The suite never builds them: ``symloc ros setup`` installs into the active environment,
    which a test must leave as it found it. The README's test command runs it first.
    """
    missing = []
    importlib.invalidate_caches()
    for m in ("tf2_msgs.msg", "nav2_msgs.msg", "nav2_msgs.srv", "bond.msg"):
        try:
            importlib.import_module(m)
        except ImportError:
            missing.append(m.split(".")[0])
    if not missing:
        return None
    return f"{', '.join(sorted(set(missing)))} not importable: run `symloc ros setup` once"


@dataclass
class Run:
    """What the run recorded (see the module docstring)."""

    tf_reason: str | None
    states: list[tuple[str, int]] = field(default_factory=list)
    statuses: list[NodeStatus] = field(default_factory=list)
    transforms: list[tuple[float, np.ndarray]] = field(default_factory=list)
    truth: dict[float, np.ndarray] = field(default_factory=dict)
    odom: dict[float, np.ndarray] = field(default_factory=dict)
    services: dict[str, bool] = field(default_factory=dict)
    bond: list[Any] = field(default_factory=list)
    amcl_poses: list[Any] = field(default_factory=list)
    clouds: list[Any] = field(default_factory=list)
    goals: int = -1
    requests: int = 0
    after_reinit: list[NodeStatus] = field(default_factory=list)
    after_set_pose: list[NodeStatus] = field(default_factory=list)
    transforms_after_reinit: int = -1
    inactive_answers: int = -1
    parameter_get: Any = None
    log: str = ""


def _quat_xyzw(q: tuple[float, float, float, float]) -> dict[str, float]:
    return dict(zip("xyzw", q, strict=True))


def _static(parent: str, child: str, xyz: Any, q: Any) -> dict[str, Any]:
    return {
        "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": parent},
        "child_frame_id": child,
        "transform": {"translation": dict(zip("xyz", xyz, strict=True)), "rotation": _quat_xyzw(q)},
    }


class Nav2Side:
    """The test's node: lifecycle and service clients, sensor publishers, output listeners."""

    def __init__(self, domain_id: int, with_tf: bool) -> None:
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import PoseWithCovarianceStamped
        from lifecycle_msgs.srv import ChangeState, GetState
        from nav_msgs.msg import OccupancyGrid, Odometry
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import Image, LaserScan
        from std_srvs.srv import Empty

        self.with_tf = with_tf
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=domain_id)
        self.node = rclpy.create_node("nav2_side", context=self.ctx)
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)
        n = self.node
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self.types: dict[str, Any] = {
            "map": OccupancyGrid,
            "scan": LaserScan,
            "image": Image,
            "odom": Odometry,
        }
        self.pub = {
            "map": n.create_publisher(OccupancyGrid, "map", latched),
            "scan": n.create_publisher(LaserScan, "scan", 50),
            "image": n.create_publisher(Image, "camera/image_raw", 10),
            "odom": n.create_publisher(Odometry, "odom", 50),
        }
        self.statuses: list[NodeStatus] = []
        self.transforms: list[tuple[float, np.ndarray]] = []
        self.bond: list[Any] = []
        self.amcl_poses: list[Any] = []
        self.clouds: list[Any] = []
        self.goals: list[Any] = []
        from geometry_msgs.msg import PoseStamped

        for topic in ("goal_pose", "symloc/goal"):  # requests are off by default (issue 27)
            n.create_subscription(PoseStamped, topic, self.goals.append, 50)
        n.create_subscription(
            DiagnosticArray, "symloc/status", lambda m: self.statuses.append(status_from_msg(m)), 50
        )
        n.create_subscription(
            PoseWithCovarianceStamped, "amcl_pose", self.amcl_poses.append, latched
        )
        self.get_state = n.create_client(GetState, "amcl/get_state")
        self.change_state = n.create_client(ChangeState, "amcl/change_state")
        self.reinit = n.create_client(Empty, "reinitialize_global_localization")
        self.nomotion = n.create_client(Empty, "request_nomotion_update")
        self.set_pose: Any = None
        if with_tf:
            from bond.msg import Status as BondStatus
            from nav2_msgs.msg import ParticleCloud
            from nav2_msgs.srv import SetInitialPose
            from tf2_msgs.msg import TFMessage

            self.types["tf"] = self.types["tf_static"] = TFMessage
            self.pub["tf"] = n.create_publisher(TFMessage, "/tf", 100)
            self.pub["tf_static"] = n.create_publisher(TFMessage, "/tf_static", latched)
            n.create_subscription(TFMessage, "/tf", self._on_tf, 100)
            n.create_subscription(BondStatus, "bond", self.bond.append, 100)
            n.create_subscription(
                ParticleCloud,
                "particle_cloud",
                self.clouds.append,
                QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT),
            )
            self.set_pose = n.create_client(SetInitialPose, "set_initial_pose")

    def _on_tf(self, msg: Any) -> None:
        for t in msg.transforms:
            if t.header.frame_id == "map" and t.child_frame_id == "odom":
                stamp = t.header.stamp.sec + t.header.stamp.nanosec * 1e-9
                q = t.transform.rotation
                pose = np.array(
                    [
                        t.transform.translation.x,
                        t.transform.translation.y,
                        2.0 * math.atan2(q.z, q.w),
                    ]
                )
                self.transforms.append((stamp, pose))

    def send(self, key: str, fields: dict[str, Any]) -> None:
        self.pub[key].publish(build_rclpy(self.types[key], fields))

    def spin_until(self, cond: Any, timeout: float) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if cond():
                return True
            self.ex.spin_once(timeout_sec=0.02)
        return bool(cond())

    def call(self, client: Any, request: Any, timeout: float = STEP_TIMEOUT) -> Any:
        if not client.wait_for_service(timeout_sec=timeout):
            return None
        future = client.call_async(request)
        self.spin_until(future.done, timeout)
        return future.result() if future.done() else None

    def state(self) -> int:
        from lifecycle_msgs.srv import GetState

        res = self.call(self.get_state, GetState.Request())
        return -1 if res is None else int(res.current_state.id)

    def transition(self, transition_id: int) -> bool:
        from lifecycle_msgs.srv import ChangeState

        req = ChangeState.Request()
        req.transition.id = transition_id
        res = self.call(self.change_state, req)
        return bool(res is not None and res.success)

    def answer(self, stamp: float, since: int, timeout: float = STEP_TIMEOUT) -> NodeStatus | None:
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


class Robot:
    """The simulated robot as nav2 sees it: TF for odometry and the laser, a mirrored scan."""

    def __init__(self, sim: Any, side: Nav2Side) -> None:
        self.sim = sim
        self.side = side

    def odometry(self) -> None:
        reading = self.sim.odometry()
        if self.side.with_tf:
            t = transform_fields(
                reading.pose, stamp=reading.stamp, parent="odom", child="base_footprint"
            )
            self.side.send("tf", {"transforms": [t]})
        else:
            self.side.send(
                "odom",
                odometry_to_fields(reading, frame_id="odom", child_frame_id="base_footprint"),
            )

    def scan(self) -> tuple[float, dict[str, Any]]:
        sim = self.sim
        upright = simulate_scan(
            sim.scenario.room.world,
            compose(sim.body.pose, LASER_UPRIGHT),
            sim.scenario.preset,
            sim.rng,
            stamp=sim.time,
            frame_id="laser",
        )
        return sim.time, scan_to_fields(mirror(upright))

    def base_scan(self) -> Any:
        """What the robot's own controller uses to avoid walls (a scan from the base)."""
        sim = self.sim
        return simulate_scan(
            sim.scenario.room.world, sim.body.pose, sim.scenario.preset, noise=False
        )


def _step(robot: Robot, run: Run, *, retries: int = 2) -> NodeStatus:
    side, sim = robot.side, robot.sim
    for _ in range(retries + 1):
        robot.odometry()
        stamp, fields = robot.scan()
        run.truth[stamp] = np.asarray(sim.body.pose, dtype=float).copy()
        run.odom[stamp] = np.asarray(sim.odometry().pose, dtype=float).copy()
        since = len(side.statuses)
        side.send("scan", fields)
        st = side.answer(stamp, since)
        if st is not None:
            return st
    raise AssertionError(f"no status from the node for the scan at {sim.time:.2f} s")


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    tf_reason = _interfaces()
    if os.environ.get("SYMLOC_TEST_WITHOUT_TF") == "1":  # exercise the fallback by hand
        tf_reason = "SYMLOC_TEST_WITHOUT_TF=1"
    with_tf = tf_reason is None
    tmp = tmp_path_factory.mktemp("nav2")
    sim = prepare_session(tmp / "assets", room="square", seed=21, map_yaml="")
    extras: dict[str, Any] = {
        "visual_map": sim.params.visual_map,
        "vocabulary": sim.params.vocabulary,
        "lidar_preset": sim.params.lidar_preset,
        "laser_frame_id": "laser",
        "camera_frame_id": "camera",
        "sensor_qos": "reliable",
        "seed": 21,
    }
    if not with_tf:  # no /tf: odometry from the topic, the laser's mount from parameters
        extras.update(
            odom_source="topic",
            laser_pose_source="parameters",
            laser_pose=[float(v) for v in LASER_UPRIGHT],
            laser_upside_down=True,
        )
    extras_path = tmp / "symloc_extras.yaml"
    extras_path.write_text(yaml.safe_dump({"amcl": {"ros__parameters": extras}}))
    domain = random.randint(1, 100)
    env = dict(os.environ)
    env.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    env["PYTHONUNBUFFERED"] = "1"
    env.pop("ROS_LOCALHOST_ONLY", None)
    log_path = tmp / "node.log"
    log = log_path.open("w")
    cmd = [sys.executable, "-m", "symloc.cli.main", "ros", "node", "--ros-args"]
    cmd += ["--params-file", str(DATA / "main.yaml"), "--params-file", str(extras_path)]
    proc = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ.pop("ROS_LOCALHOST_ONLY", None)
    side = Nav2Side(domain, with_tf)
    rec = Run(tf_reason=tf_reason)
    try:
        _play(sim, side, rec, proc)
    finally:
        rec.statuses = list(side.statuses)
        rec.transforms = list(side.transforms)
        rec.bond = list(side.bond)
        rec.amcl_poses = list(side.amcl_poses)
        rec.clouds = list(side.clouds)
        rec.goals = len(side.goals)
        rec.requests = sum(1 for s in side.statuses if s.request is not None)
        side.close()
        stop_node(proc)
        log.close()
        rec.log = log_path.read_text()
    return rec


def _play(sim: Any, side: Nav2Side, rec: Run, proc: Any) -> None:
    from std_srvs.srv import Empty

    robot = Robot(sim, side)
    rec.states.append(("start", side.state()))
    assert rec.states[-1][1] == UNCONFIGURED, "the node did not come up unconfigured"
    # nav2's side is up before the node is active: the map, the robot's geometry, odometry
    side.send("map", grid_to_fields(sim.grid, stamp=0.0))
    if side.with_tf:
        side.send(
            "tf_static",
            {
                "transforms": [
                    _static("base_footprint", "base_link", *BASE_LINK),
                    _static("base_link", "laser", *LASER),
                ]
            },
        )
    robot.odometry()
    rec.states.append(("configure", side.state() if side.transition(CONFIGURE) else -1))
    # a scan while inactive is ignored, as nav2_amcl does
    stamp, fields = robot.scan()
    since = len(side.statuses)
    side.send("scan", fields)
    side.spin_until(lambda: False, 0.5)
    rec.inactive_answers = sum(1 for s in side.statuses[since:] if abs(s.stamp - stamp) < 1e-6)
    rec.states.append(("activate", side.state() if side.transition(ACTIVATE) else -1))
    assert rec.states[-1][1] == ACTIVE, f"activation failed: {rec.states}"

    st = _step(robot, rec)
    centering = CenteringConfig()
    calm = 0
    while sim.time < 60.0:
        if st.request is None and st.status in (Status.TRACKING, Status.AMBIGUOUS):
            calm += 1
            if calm >= 3:
                break
        else:
            calm = 0
        if st.request is not None and st.request.kind.value == "capture_image":
            side.send("image", image_to_fields(sim.image(), stamp=sim.time, frame_id="camera"))
            side.spin_until(lambda: False, 0.3)
            st = _step(robot, rec)
            continue
        v, w = drive_command(st.status, st.request, robot.base_scan(), centering)
        sim.drive(v, w)
        st = _step(robot, rec)
        if "request_nomotion_update" not in rec.services and st.status is Status.TRACKING:
            rec.services["request_nomotion_update"] = (
                side.call(side.nomotion, Empty.Request()) is not None
            )
    # the end pose, through map -> odom or amcl_pose (checked by the tests)
    for _ in range(3):
        st = _step(robot, rec)
    side.spin_until(lambda: False, 0.5)
    n_tf = len(side.transforms)
    # reinitialize_global_localization: the pose is forgotten, no new map -> odom
    rec.services["reinitialize_global_localization"] = (
        side.call(side.reinit, Empty.Request()) is not None
    )
    for _ in range(4):
        rec.after_reinit.append(_step(robot, rec))
    side.spin_until(lambda: False, 0.5)
    rec.transforms_after_reinit = len(side.transforms) - n_tf
    if side.set_pose is not None:
        from nav2_msgs.srv import SetInitialPose

        req = SetInitialPose.Request()
        fields = pose_with_covariance_to_fields(
            sim.body.pose, np.diag([0.05**2, 0.05**2, math.radians(3) ** 2]), stamp=sim.time
        )
        req.pose = build_rclpy(type(req.pose), fields)
        rec.services["set_initial_pose"] = side.call(side.set_pose, req) is not None
        for _ in range(3):
            st = _step(robot, rec)
            rec.after_set_pose.append(st)
            if st.request is not None and st.request.kind.value == "capture_image":
                # the room is symmetric: the camera may veto the operator's choice of copy
                side.send("image", image_to_fields(sim.image(), stamp=sim.time, frame_id="camera"))
                side.spin_until(lambda: False, 0.3)
        side.spin_until(lambda: False, 0.5)
    rec.parameter_get = _get_parameter(side, "alpha1")
    rec.states.append(("deactivate", side.state() if side.transition(DEACTIVATE) else -1))
    # like nav2's manager, wait (bondcpp's disconnect timeout) for the node to say it broke up
    side.spin_until(lambda: any(not b.active for b in side.bond), 2.0)
    rec.states.append(("cleanup", side.state() if side.transition(CLEANUP) else -1))
    assert proc.poll() is None, "the node died"


def _get_parameter(side: Nav2Side, name: str) -> Any:
    from rcl_interfaces.srv import GetParameters

    client = side.node.create_client(GetParameters, "amcl/get_parameters")
    res = side.call(client, GetParameters.Request(names=[name]))
    return None if res is None or not res.values else res.values[0].double_value


def _at(table: dict[float, np.ndarray], stamp: float) -> np.ndarray:
    """The entry of ``table`` recorded for the scan at ``stamp`` (stamps travel as text)."""
    key = min(table, key=lambda k: abs(k - stamp))
    assert abs(key - stamp) < 1e-6, f"nothing recorded at {stamp}"
    return table[key]


def _need_tf(run: Run) -> None:
    if run.tf_reason is not None:
        pytest.skip(f"TF part skipped: {run.tf_reason}")


def test_lifecycle_unconfigured_to_active_and_back(run: Run) -> None:
    assert run.states == [
        ("start", UNCONFIGURED),
        ("configure", INACTIVE),
        ("activate", ACTIVE),
        ("deactivate", INACTIVE),
        ("cleanup", UNCONFIGURED),
    ], run.log[-3000:]
    assert run.inactive_answers == 0, "the node answered a scan while inactive"
    assert "configure failed" not in run.log


def test_nav2_params_file_is_read_as_ros_parameters(run: Run) -> None:
    assert run.parameter_get == pytest.approx(0.2)  # alpha1 of nav2's main-branch file
    assert "base_footprint" in run.log  # nav2's base_frame_id, not symloc's default


def test_services_answer(run: Run) -> None:
    assert run.services.get("request_nomotion_update") is True
    assert run.services.get("reinitialize_global_localization") is True
    assert run.after_reinit
    assert all(s.status is not Status.TRACKING for s in run.after_reinit)


def test_localized_with_the_upside_down_offset_laser(run: Run) -> None:
    tracked = [s for s in run.statuses if s.status is Status.TRACKING and s.pose is not None]
    assert tracked, "never tracking: " + run.log[-3000:]
    before_reinit = [s for s in tracked if s.stamp < min(x.stamp for x in run.after_reinit)]
    last = before_reinit[-1]
    truth = _at(run.truth, last.stamp)
    err = float(np.hypot(*(last.pose[:2] - truth[:2])))
    head = abs(float(wrap_angle(last.pose[2] - truth[2])))
    print(f"status pose at the end: {err:.4f} m, {math.degrees(head):.2f} deg")
    assert err < 0.1
    assert head < math.radians(5.0)


def test_map_to_odom_with_odometry_is_the_truth_at_the_end(run: Run) -> None:
    _need_tf(run)
    end = min(s.stamp for s in run.after_reinit)
    sent = [(t, p) for t, p in run.transforms if t - 1.0 < end]
    assert sent, "no map -> odom transform was broadcast"
    t, map_from_odom = sent[-1]
    scan_stamp = t - 1.0  # stamped with its scan's time + transform_tolerance (1.0 s)
    est = compose(map_from_odom, _at(run.odom, scan_stamp))
    truth = _at(run.truth, scan_stamp)
    err = float(np.hypot(*(est[:2] - truth[:2])))
    head = abs(float(wrap_angle(est[2] - truth[2])))
    print(f"map -> odom (+) odometry at the end: {err:.4f} m, {math.degrees(head):.2f} deg")
    assert err < 0.1
    assert head < math.radians(5.0)


def test_no_transform_before_the_pose_is_earned(run: Run) -> None:
    _need_tf(run)
    by_stamp = {round(s.stamp, 6): s for s in run.statuses}
    first_tracking = min(s.stamp for s in run.statuses if s.status is Status.TRACKING)
    for t, _ in run.transforms:
        scan = round(t - 1.0, 6)
        assert scan >= round(first_tracking, 6), f"transform for the scan at {scan} before tracking"
        st = by_stamp[scan]
        # a confirmed pose, or the last one re-sent while the localizer holds it (a claim only
        # withheld at this scan: nav2_amcl re-sends its transform between filter updates)
        assert st.status is Status.TRACKING or st.values["map_to_odom"].startswith("re-sent"), (
            f"transform sent at {scan} while not tracking: {st.reason}"
        )
    assert run.transforms_after_reinit == 0, "map -> odom sent after the pose was forgotten"


def test_set_initial_pose_resumes_tracking_and_transforms(run: Run) -> None:
    _need_tf(run)
    assert run.services.get("set_initial_pose") is True
    assert run.after_set_pose[-1].status is Status.TRACKING, run.after_set_pose[-1].reason
    resumed = [t for t, _ in run.transforms if t - 1.0 >= run.after_set_pose[0].stamp - 1e-6]
    assert resumed, "map -> odom did not resume after set_initial_pose"


def test_bond_and_weighted_particle_cloud(run: Run) -> None:
    _need_tf(run)
    assert any(b.id == "amcl" and b.active for b in run.bond), "no bond heartbeat"
    assert any(b.id == "amcl" and not b.active for b in run.bond), "the bond was not broken"
    assert run.clouds, "no nav2_msgs/ParticleCloud"
    weights = [p.weight for p in run.clouds[-1].particles]
    assert weights
    assert abs(sum(weights) - 1.0) < 1e-3


def test_no_goal_is_sent_unless_asked(run: Run) -> None:
    """The localizer asked to move the robot (in the status) but nothing went to nav2's
    ``goal_pose`` or ``symloc/goal``: ``publish_goals`` is off by default."""
    assert run.requests > 0, "the run never needed the robot to move"
    assert run.goals == 0
