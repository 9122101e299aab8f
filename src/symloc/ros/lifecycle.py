"""The symloc node as nav2 expects its localizer: a lifecycle node named ``amcl``.

:class:`LocalizationNode` is an rclpy lifecycle node (``rclpy.lifecycle``) around
:class:`~symloc.ros.core.NodeCore`, with nav2_amcl's interface:

- **Lifecycle** (``amcl/get_state``, ``amcl/change_state``, driven by nav2's
  ``lifecycle_manager_localization`` or ``nav2_simple_commander``): *configure* reads the
  parameters (an invalid one fails the transition, naming it; an unknown name is warned about
  and ignored, as nav2_amcl does) and creates the
  subscriptions, publishers and services; *activate* starts localizing (scans before it are
  ignored, as nav2_amcl does; maps, TF and odometry are kept), applies ``set_initial_pose`` /
  ``initialize_at_saved_pose`` or an initial pose received while inactive, starts the pose
  file timer and the bond; *deactivate* stops them; *cleanup* and *shutdown* release
  everything. ``autostart_node`` (or ``symloc ros node --autostart``) runs configure and
  activate at start-up.
- **Bond**: while active the node sends nav2's bond heartbeat (``bond/msg/Status`` on
  ``bond``, id = the node name) every ``bond_heartbeat_period``, so nav2's manager forms its
  bond; without the ``bond`` interfaces (``symloc ros setup``) set the manager's
  ``bond_timeout`` to 0.
- **Parameters**: every name of :func:`symloc.ros.nav2_params.parameter_defaults` is a ROS
  parameter (``ros2 param get/set``), read from nav2's own params file; a runtime change is
  validated (an invalid value is refused with the reason) and rebuilds the localizer on the
  new settings (the tracked pose is kept); changed topics are subscribed again.
- **TF**: odometry from ``/tf`` (``odom_source: tf``), the laser's mount from ``/tf_static``,
  ``map -> odom`` on ``/tf`` (:mod:`symloc.ros.tf` says what is sent while not tracking).
- **Services**: ``reinitialize_global_localization`` and ``request_nomotion_update``
  (std_srvs/Empty), ``set_initial_pose`` (nav2_msgs/SetInitialPose).
- **Topics**: ``amcl_pose``, ``particle_cloud`` (nav2_msgs/ParticleCloud with weights when
  ``nav2_msgs`` is built, geometry_msgs/PoseArray otherwise), ``initialpose`` as in nav2, and
  symloc's own (``symloc/status``, ``symloc/candidates``, ``symloc/goal`` with
  ``publish_goals``, ``symloc/capture_request``, camera inputs; :mod:`symloc.ros.node`).
- **Scans** wait for the odometry at their stamp (:meth:`NodeCore.offer_scan
  <symloc.ros.core.NodeCore.offer_scan>`, nav2_amcl's tf2 message filter): they are answered
  from the odometry callback, and a timer drops those that waited past ``transform_tolerance``.

``tf2_msgs``, ``nav2_msgs`` and ``bond`` are not on PyPI: ``symloc ros setup`` builds them
(:mod:`symloc.ros.interfaces`). Without them the node still runs: odometry from the topic,
the laser pose from ``laser_pose``, no ``map -> odom``, a PoseArray particle cloud, no
``set_initial_pose`` service and no bond; it says so at configure.
"""

from __future__ import annotations

import importlib
import math
import time
import uuid
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.parameter import Parameter

from symloc.errors import ConfigurationError, SymlocError
from symloc.files.atomic import atomic_write_text
from symloc.geometry import wrap_angle
from symloc.grid.map_io import load_map, read_map_yaml
from symloc.mcl.warmup import warm_up
from symloc.msgs.build import build_rclpy
from symloc.msgs.header import header_fields, header_frame, header_stamp
from symloc.msgs.pose import pose_fields, pose_with_covariance_from_msg
from symloc.ros.assemble import check_files
from symloc.ros.core import NodeCore, Outputs
from symloc.ros.nav2_params import (
    WITHOUT_EFFECT,
    node_params_from_ros,
    parameter_defaults,
    ros_values,
    seeded_from_time,
)
from symloc.ros.params import NodeParams
from symloc.ros.tf import transforms_from_msg
from symloc.vision.tree_descent import warm_up as warm_up_descent

__all__ = ["DEFAULT_NODE_NAME", "LocalizationNode", "load_saved_pose", "save_pose"]

DEFAULT_NODE_NAME = "amcl"
#: nav2_amcl's initial covariance when it starts from a pose without one (0.5 m, 15 deg).
INITIAL_COVARIANCE = np.diag([0.25, 0.25, (math.pi / 12.0) ** 2])
#: bondcpp's heartbeat timeout that nav2's lifecycle nodes announce [s].
BOND_HEARTBEAT_TIMEOUT = 4.0
#: bondcpp's disconnect timeout: how long a broken bond keeps saying so [s].
BOND_DISCONNECT_TIMEOUT = 2.0

#: Outputs built and published only while someone listens (RViz displays).
_ON_DEMAND = frozenset({"particle_cloud", "candidates"})

Ok = TransitionCallbackReturn.SUCCESS
Failed = TransitionCallbackReturn.FAILURE


def _optional(module: str, name: str) -> Any:
    """``module.name`` or None when the interface package is not installed."""
    try:
        return getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError):
        return None


def save_pose(path: str | Path, pose: Any, stamp: float, frame_id: str) -> None:
    """Write ``pose`` (3,) in nav2_amcl's saved-pose format (atomically: a temporary file,
    then a rename), as its ``save_pose_rate`` timer does."""
    x, y, yaw = (float(v) for v in np.asarray(pose, dtype=np.float64).reshape(3))
    atomic_write_text(
        path,
        f"timestamp: {stamp:.9f}\nframe_id: {frame_id}\n"
        f"x: {x:.6f}\ny: {y:.6f}\nz: 0.000000\nyaw: {yaw:.6f}\n",
    )


def load_saved_pose(path: str | Path) -> tuple[np.ndarray[Any, Any], str]:
    """``(pose (3,), frame_id)`` from a nav2_amcl saved-pose file.

    Raises
    ------
    ConfigurationError
        The file is missing or a value is not a number.
    """
    try:
        text = Path(path).read_text()
    except OSError as err:
        raise ConfigurationError(f"saved_pose_filepath: cannot read {path} ({err})") from err
    values: dict[str, str] = {}
    for line in text.splitlines():
        if not line.strip() or line.lstrip().startswith("#") or ":" not in line:
            continue
        key, _, value = line.partition(":")
        values[key.strip()] = value.strip()
    try:
        pose = np.array([float(values.get(k, "0")) for k in ("x", "y", "yaw")])
    except ValueError as err:
        raise ConfigurationError(f"saved_pose_filepath: {path}: {err}") from err
    if not np.all(np.isfinite(pose)):
        raise ConfigurationError(f"saved_pose_filepath: {path}: non-finite pose {pose}")
    return pose, values.get("frame_id", "")


class LocalizationNode(LifecycleNode):
    """nav2_amcl's drop-in: see the module docstring.

    Parameters
    ----------
    node_name : str
        ``amcl`` by default, the name nav2's launch files and lifecycle manager use.
    params : NodeParams, optional
        Defaults for the ROS parameters (e.g. from ``symloc ros node --params FILE``); the
        parameters of ``--ros-args`` (``--params-file``, ``-p``) override them.
    context : rclpy Context, optional
    cli_args : sequence of str, optional
        ROS arguments (``--ros-args ...``).
    factory : callable, optional
        ``factory(grid, params) -> Localizer`` (tests inject a lighter one).
    """

    def __init__(
        self,
        node_name: str = DEFAULT_NODE_NAME,
        *,
        params: NodeParams | None = None,
        context: Any = None,
        cli_args: Sequence[str] | None = None,
        factory: Callable[..., Any] | None = None,
    ) -> None:
        super().__init__(node_name, context=context, cli_args=list(cli_args or []) or None)
        from rcl_interfaces.msg import ParameterDescriptor

        self.factory = factory
        self.core: NodeCore | None = None
        self.params: NodeParams | None = None
        self.active = False
        self._sub_handles: list[Any] = []
        self._pub_handles: dict[str, Any] = {}
        self._types: dict[str, Any] = {}
        self._srv_handles: list[Any] = []
        self._timer_handles: list[Any] = []
        self._bond: _Bond | None = None
        self._broken_bonds: list[_Bond] = []
        self._odom_sub: Any = None
        self._odom_feed: Callable[[Any], None] | None = None
        self._pending_pose: tuple[Any, Any] | None = None
        self._last_pose: tuple[Any, Any, float] | None = None
        self.tf_message = _optional("tf2_msgs.msg", "TFMessage")
        self.particle_cloud_type = _optional("nav2_msgs.msg", "ParticleCloud")
        self.set_initial_pose_type = _optional("nav2_msgs.srv", "SetInitialPose")
        self.empty_service = _optional("std_srvs.srv", "Empty")
        self.bond_status = _optional("bond.msg", "Status")
        defaults = parameter_defaults()
        if params is not None:
            defaults.update(ros_values(params))
        descriptor = ParameterDescriptor(dynamic_typing=True)
        self._declared = list(defaults)
        for name, value in defaults.items():
            self.declare_parameter(name, value, descriptor)
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self.get_logger().info(
            f"symloc localization node '{node_name}' (lifecycle): waiting for configure"
            f"{'' if self.tf_message else '; tf2_msgs not built (run symloc ros setup)'}"
        )
        if self.get_parameter("autostart_node").value:
            self.autostart()

    # ------------------------------------------------------------------ parameters

    def _values(self, changes: Sequence[Parameter[Any]] = ()) -> dict[str, Any]:
        values = {n: self.get_parameter(n).value for n in self._declared}
        for p in changes:
            values[p.name] = p.value
        return values

    def unknown_parameters(self) -> list[str]:
        """Names the params file gave this node that it does not know (warned about at
        configure and ignored, as nav2_amcl ignores names it does not declare)."""
        overrides = getattr(self, "_parameter_overrides", {}) or {}
        known = set(self._declared) | {"use_sim_time", "start_type_description_service"}
        return sorted(n for n in overrides if n not in known and not n.startswith("qos_overrides."))

    def read_params(self) -> NodeParams:
        """The node's settings from its ROS parameters (raises ConfigurationError on an invalid
        value); unknown names are warned about and ignored, as nav2_amcl does."""
        log = self.get_logger()
        for name in self.unknown_parameters():
            log.warning(
                f"parameter {name!r}: unknown to symloc, ignored (as nav2_amcl ignores names it"
                " does not declare; symloc's names: symloc.ros.nav2_params)"
            )
        values = self._values()
        for name in ("accept_map_updates",):
            if values.get(name) is not None and values.get(name) != WITHOUT_EFFECT[name][0]:
                log.warning(f"parameter {name!r}: {WITHOUT_EFFECT[name][1]}")
        params = node_params_from_ros(values, on_unknown=lambda why: log.warning(why))
        if seeded_from_time(values):
            log.info(
                f"random_seed {values['random_seed']}: filter seeded from the time ({params.seed})"
            )
        return params

    def _validate_parameters(self, changes: list[Parameter[Any]]) -> Any:
        from rcl_interfaces.msg import SetParametersResult

        if self.core is None:  # not configured: read at configure
            return SetParametersResult(successful=True)
        try:
            new = node_params_from_ros(self._values(changes))
            if self.params is None or (new.visual_map, new.vocabulary) != (
                self.params.visual_map,
                self.params.vocabulary,
            ):
                check_files(new)
        except ConfigurationError as err:
            return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, changes: list[Parameter[Any]]) -> None:
        if self.core is None or self.params is None:
            return
        if all(p.name.startswith("qos_overrides.") or p.name == "use_sim_time" for p in changes):
            return  # declared by rclpy with the scan subscription; read at subscription time
        try:
            new = node_params_from_ros(self._values())
        except ConfigurationError as err:  # validated before; keep the old settings
            self.get_logger().error(f"parameters not applied: {err}")
            return
        old = self.params
        self.params = new
        self.core.reconfigure(new)
        topics = [n for n in vars(new) if n.endswith(("_topic", "_source", "sensor_qos"))]
        if any(getattr(old, n) != getattr(new, n) for n in topics):
            self._destroy_io()
            self._create_io()
            if self.active:
                for pub in self._pub_handles.values():
                    if hasattr(pub, "on_activate"):
                        pub.on_activate(None)
        names = ", ".join(p.name for p in changes)
        self.get_logger().info(f"parameters changed ({names}): localizer rebuilt on them")

    # ------------------------------------------------------------------ lifecycle

    def autostart(self) -> None:
        """Configure and activate now (nav2's ``autostart_node``)."""
        if self.trigger_configure() == Ok:
            self.trigger_activate()

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        log = self.get_logger()
        try:
            params = self.read_params()
        except ConfigurationError as err:
            log.error(f"configure failed: {err}")
            return Failed
        try:
            # as nav2 fails configure for a bad map: a visual map or vocabulary that cannot
            # be used fails here, not at every map build while the node answers `lost`
            check_files(params)
        except ConfigurationError as err:
            log.error(f"configure failed: {err}")
            return Failed
        for name in ("odom_source", "laser_pose_source"):
            if getattr(params, name) == "tf" and self.tf_message is None:
                other = "topic" if name == "odom_source" else "parameters"
                log.error(
                    f"configure failed: {name} is tf but tf2_msgs is not installed: run"
                    f" `symloc ros setup`, or set {name}: {other}"
                )
                return Failed
        self.params = params
        self.core = NodeCore(
            params,
            factory=self.factory,
            warn=lambda text: log.warning(text),
            use_tf=self.tf_message is not None,
        )
        self._create_io()
        self._create_services()
        if params.map_yaml:
            try:
                meta = read_map_yaml(params.map_yaml)
                used = self.core.set_map(
                    load_map(params.map_yaml),
                    map_std_xy=meta.map_std_xy,
                    map_error_field=meta.map_error_field,
                )
            except SymlocError as err:
                log.error(f"configure failed: map_yaml: {err}")
                self._release()
                return Failed
            if not used:
                log.error(f"configure failed: map_yaml: {params.map_yaml}: {self.core.map_refused}")
                self._release()
                return Failed
        if not params.always_reset_initial_pose and self._last_pose is not None:
            self._pending_pose = (self._last_pose[0], self._last_pose[1])
        # the compiled kernels' first calls (a compile on a fresh install, a cache load
        # after) happen here, while the node is inactive, not at its first scan
        warm_up(params.amcl)
        warm_up_descent()  # the BoW transform's kernel, before the first camera image
        missing = [
            name
            for name, cls in (
                ("tf2_msgs (no map -> odom, no /tf input)", self.tf_message),
                (
                    "nav2_msgs (particle_cloud as PoseArray, no set_initial_pose)",
                    self.particle_cloud_type,
                ),
                ("std_srvs (no services)", self.empty_service),
                ("bond (no bond: set the manager's bond_timeout to 0)", self.bond_status),
            )
            if cls is None
        ]
        if missing:
            log.warning("interfaces missing (symloc ros setup builds them): " + "; ".join(missing))
        log.info(
            f"configured: scan '{params.scan_topic}', map '{params.map_topic}', odometry from"
            f" {'/tf' if params.odom_source == 'tf' else repr(params.odom_topic)},"
            f" frames {params.global_frame_id} / {params.odom_frame_id} / {params.base_frame_id}"
        )
        return super().on_configure(state)

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        assert self.params is not None
        assert self.core is not None
        p = self.params
        log = self.get_logger()
        if p.set_initial_pose:
            if p.initialize_at_saved_pose and Path(p.saved_pose_filepath).is_file():
                log.warning("both initial_pose parameters and a saved pose exist: using the former")
            self._pending_pose = (np.array(p.initial_pose), INITIAL_COVARIANCE)
        elif p.initialize_at_saved_pose:
            try:
                pose, frame = load_saved_pose(p.saved_pose_filepath)
            except ConfigurationError as err:
                log.error(f"activate failed: initialize_at_saved_pose: {err}")
                return Failed
            if frame and frame != p.global_frame_id:
                log.error(f"activate failed: the saved pose is in frame {frame!r}")
                return Failed
            self._pending_pose = (pose, INITIAL_COVARIANCE)
        self._apply_pending_pose()
        self.active = True
        # held scans whose odometry never comes are dropped (and answered) after the tolerance
        self._timer_handles.append(
            self.create_timer(max(0.05, p.transform_tolerance / 4.0), self._answer_held)
        )
        if p.save_pose_rate > 0.0:
            self._timer_handles.append(self.create_timer(1.0 / p.save_pose_rate, self._save_pose))
        if p.bond_heartbeat_period > 0.0 and self.bond_status is not None:
            self._bond = _Bond(self, self.bond_status, p.bond_heartbeat_period)
        log.info("activated: localizing")
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.active = False
        self._stop_activity()
        self.get_logger().info("deactivated")
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        self._release()
        self.get_logger().info("cleaned up")
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.active = False
        self._stop_activity()
        self._release()
        return super().on_shutdown(state)

    def _stop_activity(self) -> None:
        for timer in self._timer_handles:
            self.destroy_timer(timer)
        self._timer_handles = []
        if self._bond is not None:
            self._bond.breakup()
            # the closed ones are done: a node cycled active/inactive keeps no list of them
            self._broken_bonds = [b for b in self._broken_bonds if not b.closed] + [self._bond]
            self._bond = None

    def _release(self) -> None:
        for bond in self._broken_bonds:
            bond.close()
        self._broken_bonds = []
        self._destroy_io()
        for srv in self._srv_handles:
            self.destroy_service(srv)
        self._srv_handles = []
        self.core = None

    # ------------------------------------------------------------------ topics

    def _create_io(self) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import PoseArray, PoseStamped, PoseWithCovarianceStamped
        from nav_msgs.msg import OccupancyGrid, Odometry
        from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
        from rclpy.qos_overriding_options import QoSOverridingOptions
        from sensor_msgs.msg import CompressedImage, Image, LaserScan
        from std_msgs.msg import Header
        from visualization_msgs.msg import MarkerArray

        assert self.params is not None
        assert self.core is not None
        p, core = self.params, self.core
        reliable = p.sensor_qos == "reliable"
        sensor = QoSProfile(
            history=HistoryPolicy.KEEP_LAST,
            depth=50 if reliable else 5,
            reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
            durability=DurabilityPolicy.VOLATILE,
        )
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        sub = self.create_subscription
        self._sub_handles = [
            sub(
                LaserScan,
                p.scan_topic,
                self._on_scan,
                sensor,
                qos_overriding_options=QoSOverridingOptions.with_default_policies(),
            ),
            sub(OccupancyGrid, p.map_topic, self._guard(core.on_map), latched),
            sub(PoseWithCovarianceStamped, p.initialpose_topic, self._on_initialpose, 10),
        ]
        self._odom_sub, self._odom_feed = None, None
        if p.odom_source == "topic":
            self._odom_sub = sub(Odometry, p.odom_topic, self._guard(self._on_odom_msg), sensor)
            self._odom_feed = self._guard(core.on_odom)
            self._sub_handles.append(self._odom_sub)
        if self.tf_message is not None:
            tf_qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
            static_qos = QoSProfile(
                depth=100,
                reliability=ReliabilityPolicy.RELIABLE,
                durability=DurabilityPolicy.TRANSIENT_LOCAL,
            )
            on_tf = self._on_odom_tf if p.odom_source == "tf" else self._static_only
            tf_sub = sub(self.tf_message, "/tf", self._guard(on_tf), tf_qos)
            self._sub_handles.append(tf_sub)
            if p.odom_source == "tf":
                self._odom_sub, self._odom_feed = tf_sub, self._guard(core.on_tf)
            self._sub_handles.append(
                sub(self.tf_message, "/tf_static", self._guard(core.on_tf_static), static_qos)
            )
        if p.image_topic:
            self._sub_handles.append(sub(Image, p.image_topic, self._guard(core.on_image), sensor))
        if p.compressed_image_topic:
            self._sub_handles.append(
                sub(
                    CompressedImage,
                    p.compressed_image_topic,
                    self._guard(core.on_compressed_image),
                    sensor,
                )
            )
        cloud_type = self.particle_cloud_type or PoseArray
        best_effort = QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT)
        pub = self.create_lifecycle_publisher
        self._types = {
            "amcl_pose": PoseWithCovarianceStamped,
            "particle_cloud": cloud_type,
            "status": DiagnosticArray,
            "candidates": MarkerArray,
            "goal": PoseStamped,
            "capture": Header,
            "axis_pose": PoseWithCovarianceStamped,
            "tf": self.tf_message,
        }
        self._pub_handles = {
            "amcl_pose": pub(PoseWithCovarianceStamped, p.amcl_pose_topic, latched),
            "particle_cloud": pub(cloud_type, p.particle_cloud_topic, best_effort),
            "status": pub(DiagnosticArray, p.status_topic, 50),
            "candidates": pub(MarkerArray, p.candidates_topic, 10),
            "capture": pub(Header, p.capture_topic, 10),
            "axis_pose": pub(PoseWithCovarianceStamped, p.axis_pose_topic, 10),
        }
        if p.publish_goals:  # off by default: nothing commands the robot unless asked
            self._pub_handles["goal"] = pub(PoseStamped, p.goal_topic, 10)
        if self.tf_message is not None:
            self._pub_handles["tf"] = pub(
                self.tf_message,
                "/tf",
                QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE),
            )

    def _destroy_io(self) -> None:
        for s in self._sub_handles:
            self.destroy_subscription(s)
        self._sub_handles = []
        for p in self._pub_handles.values():
            self.destroy_lifecycle_publisher(p)
        self._pub_handles = {}

    def _create_services(self) -> None:
        if self.empty_service is not None:
            self._srv_handles.append(
                self.create_service(
                    self.empty_service, "reinitialize_global_localization", self._srv_global
                )
            )
            self._srv_handles.append(
                self.create_service(
                    self.empty_service, "request_nomotion_update", self._srv_nomotion
                )
            )
        if self.set_initial_pose_type is not None:
            self._srv_handles.append(
                self.create_service(
                    self.set_initial_pose_type, "set_initial_pose", self._srv_initial_pose
                )
            )

    def _static_only(self, msg: Any) -> None:
        """``/tf`` while odometry comes from the topic: frames only (no odometry from TF)."""
        assert self.core is not None
        for t in transforms_from_msg(msg):
            self.core.tf.add(t, static=False)

    def _guard(self, handler: Callable[[Any], Any]) -> Callable[[Any], None]:
        """Wrap a callback so that no exception ever takes the node down."""

        def cb(msg: Any) -> None:
            try:
                handler(msg)
            except Exception as err:  # the node must stay up: count it and go on
                if self.core is not None:
                    self.core.drop("internal error", f"{type(err).__name__}: {err}")

        return cb

    # ------------------------------------------------------------------ callbacks

    def _now(self) -> float:
        return float(self.get_clock().now().nanoseconds) * 1e-9

    def _on_scan(self, msg: Any) -> None:
        core = self.core
        if core is None or not self.active:
            return  # nav2_amcl ignores scans until it is active
        try:
            self._apply_pending_pose()
            self._drain_odometry()
            outs = core.receive_scan(msg, self._now())
        except Exception as err:  # the node must stay up; the status still goes out
            core.drop("internal error", f"{type(err).__name__}: {err}")
            outs = [core.unused_scan(None)]
        for out in outs:
            self.publish(out)

    def _on_odom_tf(self, msg: Any) -> None:
        """``/tf``: odometry (and frames); held scans it now covers are answered."""
        assert self.core is not None
        self.core.on_tf(msg)
        self._answer_held()

    def _on_odom_msg(self, msg: Any) -> None:
        """nav_msgs/Odometry (``odom_source: topic``); held scans it covers are answered."""
        assert self.core is not None
        self.core.on_odom(msg)
        self._answer_held()

    def _answer_held(self) -> None:
        core = self.core
        if core is None or not self.active or not core.held_scans:
            return
        self._drain_odometry()
        for out in core.ready_scans(self._now()):
            self.publish(out)

    def _drain_odometry(self) -> None:
        """Take the odometry messages already delivered but not yet handed to a callback.

        nav2_amcl's tf2 listener fills its buffer on a thread of its own, so its message
        filter sees every transform that has arrived. Here one executor runs every callback:
        after a long step (global localization on a loaded machine) the odometry that covers a
        held scan may sit in the subscription's queue while the scan's deadline passes, so
        the queue is emptied first (rclpy's own take, as its executor does)."""
        sub, feed = self._odom_sub, self._odom_feed
        if sub is None or feed is None:
            return
        for _ in range(1000):
            try:
                with sub.handle:
                    taken = sub.handle.take_message(sub.msg_type, sub.raw)
            except Exception:  # an rclpy without this API, or a destroyed subscription
                return
            if taken is None:
                return
            feed(taken[0])

    def publish(self, out: Outputs) -> None:
        """Publish one step's outputs (and remember the pose for the pose file)."""
        p = self.params
        assert p is not None
        est = out.estimate
        if out.amcl_pose is not None and est.pose is not None and est.covariance is not None:
            self._last_pose = (np.asarray(est.pose), np.asarray(est.covariance), out.stamp)
        # map -> odom first: nav2's costmaps and controller wait for it
        fields = {
            "tf": out.tf,
            "amcl_pose": out.amcl_pose,
            "status": out.status,
            "goal": out.goal if p.publish_goals else None,
            "capture": out.capture,
            "axis_pose": out.axis_pose,
            "candidates": out.candidates,
            "particle_cloud": out.particle_cloud,
        }
        for key, value in fields.items():
            pub = self._pub_handles.get(key)
            if value is None or pub is None:
                continue
            if key in _ON_DEMAND and pub.get_subscription_count() == 0:
                continue  # built only for a listener (a cloud of 2000 particles: ~75 ms)
            if key == "particle_cloud" and self.particle_cloud_type is not None:
                value = self._weighted_cloud(out)
                if value is None:
                    continue
            pub.publish(build_rclpy(self._types[key], value))

    def _weighted_cloud(self, out: Outputs) -> dict[str, Any] | None:
        """nav2_msgs/ParticleCloud fields: AMCL's particles and their weights."""
        assert self.core is not None
        assert self.params is not None
        last = None if self.core.localizer is None else self.core.localizer.last_result
        if last is None or last.particles is None:
            return None
        weights = last.weights
        poses = np.asarray(last.particles, dtype=np.float64).reshape(-1, 3)
        w = np.asarray(weights if weights is not None else [], dtype=np.float64).reshape(-1)
        if w.shape[0] != poses.shape[0]:
            w = np.full(poses.shape[0], 1.0 / max(1, poses.shape[0]))
        return {
            "header": header_fields(out.stamp, self.params.global_frame_id),
            "particles": [
                {"pose": pose_fields(pose), "weight": float(wi)}
                for pose, wi in zip(poses, w, strict=True)
            ],
        }

    def _on_initialpose(self, msg: Any) -> None:
        try:
            self.initial_pose(msg)
        except Exception as err:  # the node must stay up
            if self.core is not None:
                self.core.drop("internal error", f"{type(err).__name__}: {err}")

    def initial_pose(self, msg: Any) -> bool:
        """An initial pose (topic ``initialpose`` or service ``set_initial_pose``), as nav2:
        only in the global frame; while inactive it is kept for activation. Returns whether it
        was taken (now or for later)."""
        core, log = self.core, self.get_logger()
        if core is None:
            return False
        try:
            frame = header_frame(msg, "PoseWithCovarianceStamped")
            pose, cov = pose_with_covariance_from_msg(msg)
            stamp = header_stamp(msg, "PoseWithCovarianceStamped")
        except SymlocError as err:
            core.drop("initialpose: malformed", str(err))
            return False
        if frame != core.params.global_frame_id:
            core.drop(
                "initialpose: wrong frame",
                f"frame {frame!r}; initial poses must be in {core.params.global_frame_id!r}",
            )
            return False
        pose = core.carried_to_now(pose, stamp)
        self._pending_pose = (pose, cov)
        if not self.active:
            log.warning("initial pose received while inactive: applied at activation")
            return True
        return self._apply_pending_pose()

    def _apply_pending_pose(self) -> bool:
        """Hand the pending initial pose to the core once it has a map (the core keeps it
        across every rebuild of the localizer until tracking confirms it)."""
        core = self.core
        if self._pending_pose is None or core is None or core.localizer is None:
            return False
        pose, cov = self._pending_pose
        self._pending_pose = None
        pose = np.asarray(pose, dtype=np.float64).copy()
        pose[2] = wrap_angle(pose[2])
        return core.set_initial_pose(pose, np.asarray(cov, dtype=np.float64))

    def _save_pose(self) -> None:
        if not self.active or self._last_pose is None or self.params is None:
            return
        pose, _, stamp = self._last_pose
        try:
            save_pose(self.params.saved_pose_filepath, pose, stamp, self.params.global_frame_id)
        except OSError as err:
            self.get_logger().warning(f"could not save the pose: {err}")

    # ------------------------------------------------------------------ services

    def _srv_global(self, request: Any, response: Any) -> Any:
        if self.core is not None and self.core.reinitialize_global():
            self.get_logger().info("reinitialize_global_localization: global localization")
        return response

    def _srv_nomotion(self, request: Any, response: Any) -> Any:
        if self.core is not None and self.core.request_nomotion_update():
            self.get_logger().info("request_nomotion_update: the next scan updates the filter")
        return response

    def _srv_initial_pose(self, request: Any, response: Any) -> Any:
        self.initial_pose(request.pose)
        return response


class _Bond:
    """nav2's bond heartbeat (bondcpp's protocol): ``bond/msg/Status`` on ``bond`` with this
    node's name as the bond id, a fresh instance id, ``active`` true while the bond holds."""

    def __init__(self, node: LocalizationNode, status_type: Any, period: float) -> None:
        from rclpy.qos import QoSProfile, ReliabilityPolicy

        self.node = node
        self.type = status_type
        self.period = float(period)
        self.id = node.get_name()
        self.instance = str(uuid.uuid4())
        self.sister: str | None = None
        self.sister_broken = False
        self.closed = False
        self.pub = node.create_publisher(
            status_type, "bond", QoSProfile(depth=5, reliability=ReliabilityPolicy.RELIABLE)
        )
        self.sub = node.create_subscription(status_type, "bond", self._on_status, 100)
        self.timer = node.create_timer(self.period, lambda: self._send(True))
        self._send(True)

    def _on_status(self, msg: Any) -> None:
        if msg.id == self.id and msg.instance_id != self.instance:
            self.sister = msg.instance_id
            self.sister_broken = not msg.active

    def _send(self, active: bool) -> None:
        now = self.node.get_clock().now().nanoseconds * 1e-9
        self.pub.publish(
            build_rclpy(
                self.type,
                {
                    "header": header_fields(now, ""),
                    "id": self.id,
                    "instance_id": self.instance,
                    "active": active,
                    "heartbeat_timeout": BOND_HEARTBEAT_TIMEOUT,
                    "heartbeat_period": self.period,
                },
            )
        )

    def breakup(self) -> None:
        """Say the bond is broken, and keep saying so every period until the sister answers
        that it is broken too or :data:`BOND_DISCONNECT_TIMEOUT` passes (bondcpp's protocol).

        The writer stays up meanwhile: a status published just before its publisher is
        destroyed may never reach a subscriber that has not acknowledged it yet.
        """
        self.node.destroy_timer(self.timer)
        self._send(False)
        deadline = time.monotonic() + BOND_DISCONNECT_TIMEOUT

        def resend() -> None:
            if self.sister_broken or time.monotonic() > deadline:
                self.close()
            else:
                self._send(False)

        self.timer = self.node.create_timer(min(self.period, 0.25), resend)

    def close(self) -> None:
        """Destroy the timer, publisher and subscription (idempotent)."""
        if self.closed:
            return
        self.closed = True
        self.node.destroy_timer(self.timer)
        self.node.destroy_subscription(self.sub)
        self.node.destroy_publisher(self.pub)
