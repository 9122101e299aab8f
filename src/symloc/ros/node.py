"""The symloc ROS 2 node (rclpy): ``symloc ros node --params params.yaml``.

Topics (relative names, so ``--ros-args -r old:=new`` and namespaces apply; the names are also
parameters, see :class:`~symloc.ros.params.NodeParams`):

=============================  ==========================================  ====================
topic (default)                type                                        QoS
=============================  ==========================================  ====================
in  ``scan``                   sensor_msgs/LaserScan                       sensor data [1]_
in  ``odom``                   nav_msgs/Odometry                           sensor data [1]_
in  ``map``                    nav_msgs/OccupancyGrid                      reliable, transient
                                                                           local (map_server)
in  ``camera/image_raw``       sensor_msgs/Image                           sensor data [1]_
in  ``camera/image_raw/        sensor_msgs/CompressedImage                 sensor data [1]_
compressed``
in  ``initialpose``            geometry_msgs/PoseWithCovarianceStamped     reliable
out ``amcl_pose``              geometry_msgs/PoseWithCovarianceStamped     reliable, transient
                               (only while tracking, as nav2_amcl)         local, depth 1
out ``particle_cloud``         geometry_msgs/PoseArray                     best effort
out ``symloc/status``          diagnostic_msgs/DiagnosticArray [2]_        reliable
out ``symloc/candidates``      visualization_msgs/MarkerArray [2]_         reliable
out ``goal_pose``              geometry_msgs/PoseStamped, odom frame:      reliable
                               go to the centre / face / rotate
out ``symloc/capture_request`` std_msgs/Header: take an image now          reliable
=============================  ==========================================  ====================

.. [1] best effort, depth 5, like nav2_amcl's scan subscription (matches reliable and
   best-effort publishers); ``sensor_qos: reliable`` makes them reliable, depth 50.
.. [2] see :mod:`symloc.ros.status_msg` for the key / value layout.

The map frame's ``goal_pose`` of nav2 would need a pose the localizer has not earned, so the
requests of Algorithm 2 are published in the odometry frame, which the robot knows.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from symloc.errors import ConfigurationError
from symloc.ros.build import build_rclpy
from symloc.ros.core import NodeCore, Outputs
from symloc.ros.params import NodeParams

__all__ = ["SymlocNode", "rclpy_available", "run_node"]


def rclpy_available() -> bool:
    """True when rclpy and the message packages import (``pip install symloc[ros]``)."""
    try:
        import diagnostic_msgs.msg  # noqa: F401
        import geometry_msgs.msg  # noqa: F401
        import nav_msgs.msg  # noqa: F401
        import rclpy  # noqa: F401
        import sensor_msgs.msg  # noqa: F401
        import std_msgs.msg  # noqa: F401
        import visualization_msgs.msg  # noqa: F401
    except ImportError:
        return False
    return True


def _require_rclpy() -> None:
    if not rclpy_available():
        raise ConfigurationError(
            "symloc ros node needs rclpy and the ROS message packages: pip install 'symloc[ros]'"
        )


class SymlocNode:
    """The rclpy node around a :class:`~symloc.ros.core.NodeCore`.

    Parameters
    ----------
    params : NodeParams
    node_name : str
    context : rclpy Context, optional
    factory : callable, optional
        ``factory(grid, params) -> Localizer`` (tests inject a lighter one).
    """

    def __init__(
        self,
        params: NodeParams,
        *,
        node_name: str = "symloc",
        context: Any = None,
        factory: Any = None,
        cli_args: Sequence[str] | None = None,
    ) -> None:
        _require_rclpy()
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import PoseArray, PoseStamped, PoseWithCovarianceStamped
        from nav_msgs.msg import OccupancyGrid, Odometry
        from rclpy.node import Node
        from rclpy.qos import (
            DurabilityPolicy,
            HistoryPolicy,
            QoSProfile,
            ReliabilityPolicy,
        )
        from sensor_msgs.msg import CompressedImage, Image, LaserScan
        from std_msgs.msg import Header
        from visualization_msgs.msg import MarkerArray

        self.params = params
        self.node = Node(node_name, context=context, cli_args=list(cli_args or []) or None)
        log = self.node.get_logger()
        self.core = NodeCore(params, factory=factory, warn=lambda text: log.warning(text))
        self._types = {
            "amcl_pose": PoseWithCovarianceStamped,
            "particle_cloud": PoseArray,
            "status": DiagnosticArray,
            "candidates": MarkerArray,
            "goal": PoseStamped,
            "capture": Header,
        }
        reliable = params.sensor_qos == "reliable"
        sensor = QoSProfile(
            history=HistoryPolicy.KEEP_LAST,
            depth=50 if reliable else 5,
            reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
            durability=DurabilityPolicy.VOLATILE,
        )
        latched = QoSProfile(
            history=HistoryPolicy.KEEP_LAST,
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        n = self.node
        p = params
        n.create_subscription(LaserScan, p.scan_topic, self._on_scan, sensor)
        n.create_subscription(Odometry, p.odom_topic, self._guard(self.core.on_odom), sensor)
        n.create_subscription(OccupancyGrid, p.map_topic, self._guard(self.core.on_map), latched)
        if p.image_topic:
            n.create_subscription(Image, p.image_topic, self._guard(self.core.on_image), sensor)
        if p.compressed_image_topic:
            n.create_subscription(
                CompressedImage,
                p.compressed_image_topic,
                self._guard(self.core.on_compressed_image),
                sensor,
            )
        n.create_subscription(
            PoseWithCovarianceStamped,
            p.initialpose_topic,
            self._guard(self.core.on_initialpose),
            10,
        )
        self._pubs = {
            "amcl_pose": n.create_publisher(PoseWithCovarianceStamped, p.amcl_pose_topic, latched),
            "particle_cloud": n.create_publisher(
                PoseArray,
                p.particle_cloud_topic,
                QoSProfile(depth=2, reliability=ReliabilityPolicy.BEST_EFFORT),
            ),
            "status": n.create_publisher(DiagnosticArray, p.status_topic, 50),
            "candidates": n.create_publisher(MarkerArray, p.candidates_topic, 10),
            "goal": n.create_publisher(PoseStamped, p.goal_topic, 10),
            "capture": n.create_publisher(Header, p.capture_topic, 10),
        }
        if p.map_yaml:
            from symloc.grid.map_io import load_map

            self.core.set_map(load_map(p.map_yaml))
        log.info(
            f"symloc node up: mode {p.mode}, scan '{p.scan_topic}', odom '{p.odom_topic}',"
            f" map '{p.map_topic}'{' (loaded ' + p.map_yaml + ')' if p.map_yaml else ''}"
        )

    def _guard(self, handler: Any) -> Any:
        """Wrap a callback so that no exception ever takes the node down."""

        def cb(msg: Any) -> None:
            try:
                handler(msg)
            except Exception as err:  # the node must stay up: count it and go on
                self.core.drop("internal error", f"{type(err).__name__}: {err}")

        return cb

    def _on_scan(self, msg: Any) -> None:
        try:
            out = self.core.on_scan(msg)
        except Exception as err:  # the node must stay up; the status still goes out
            self.core.drop("internal error", f"{type(err).__name__}: {err}")
            out = self.core.unused_scan(None)
        self.publish(out)

    def publish(self, out: Outputs) -> None:
        """Publish one step's outputs."""
        for key in ("particle_cloud", "amcl_pose", "goal", "capture", "candidates", "status"):
            fields = getattr(out, key)
            if fields is not None:
                self._pubs[key].publish(build_rclpy(self._types[key], fields))

    def destroy(self) -> None:
        """Destroy the rclpy node."""
        self.node.destroy_node()


def run_node(params_path: str | Path, ros_args: Sequence[str] = ()) -> int:
    """Run the node until Ctrl-C (``symloc ros node``); returns the exit code."""
    _require_rclpy()
    import rclpy
    from rclpy.executors import ExternalShutdownException

    params = NodeParams.from_yaml(params_path)
    args = [sys.argv[0], *ros_args]
    rclpy.init(args=args)
    node = SymlocNode(params)
    try:
        rclpy.spin(node.node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy()
        if rclpy.ok():
            rclpy.shutdown()
    return 0
