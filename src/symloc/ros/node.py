"""The symloc ROS 2 node (rclpy): ``symloc ros node [--params params.yaml] [--ros-args ...]``.

The node is a lifecycle node named ``amcl`` that takes nav2_amcl's place
(:mod:`symloc.ros.lifecycle`: lifecycle, bond, services, nav2's params files; TF in
:mod:`symloc.ros.tf`). Topics (relative names, so ``--ros-args -r old:=new`` and namespaces
apply; the names are also parameters, see :class:`~symloc.ros.params.NodeParams`):

=============================  ==========================================  ====================
topic (default)                type                                        QoS
=============================  ==========================================  ====================
in  ``scan``                   sensor_msgs/LaserScan                       sensor data [1]_
in  ``/tf``, ``/tf_static``     tf2_msgs/TFMessage: odom -> base,           reliable (static:
                               base -> laser                               transient local)
in  ``odom``                   nav_msgs/Odometry (``odom_source: topic``)  sensor data [1]_
in  ``map``                    nav_msgs/OccupancyGrid                      reliable, transient
                                                                           local (map_server)
in  ``camera/image_raw``       sensor_msgs/Image                           sensor data [1]_
in  ``camera/image_raw/        sensor_msgs/CompressedImage                 sensor data [1]_
compressed``
in  ``initialpose``            geometry_msgs/PoseWithCovarianceStamped     reliable
out ``amcl_pose``              geometry_msgs/PoseWithCovarianceStamped     reliable, transient
                               (only while tracking, as nav2_amcl)         local, depth 1
out ``particle_cloud``         nav2_msgs/ParticleCloud (PoseArray without  best effort
                               nav2_msgs)
out ``/tf``                    tf2_msgs/TFMessage: map -> odom             reliable
out ``symloc/status``          diagnostic_msgs/DiagnosticArray [2]_        reliable
out ``symloc/candidates``      visualization_msgs/MarkerArray [2]_         reliable
out ``symloc/goal``            geometry_msgs/PoseStamped, odom frame:      reliable
                               go to the centre / face / rotate (only
                               with ``publish_goals``; off by default)
out ``symloc/capture_request`` std_msgs/Header: take an image now          reliable
out ``symloc/axis_pose``       geometry_msgs/PoseWithCovarianceStamped     reliable
                               (only with status ``axis`` [3]_)
=============================  ==========================================  ====================

.. [1] best effort, depth 5, like nav2_amcl's scan subscription (matches reliable and
   best-effort publishers); ``sensor_qos: reliable`` makes them reliable, depth 50.
.. [2] see :mod:`symloc.ros.status_msg` for the key / value layout.
.. [3] a corridor: the camera decided the heading but not where along the corridor the robot
   stands (:mod:`symloc.localizer.axis_phase`). The pose is the middle of the segment with the
   decided heading, its covariance as long as the segment (std about length / sqrt(12) along
   it) and tight across it and in heading. It is not a localized pose: nothing goes on
   ``amcl_pose`` and no ``map -> odom`` is sent, so nav2 does not plan or drive on it (as
   while lost); ``symloc/status`` says ``axis`` (level WARN) with the segment.

The map frame's ``goal_pose`` of nav2 would need a pose the localizer has not earned, so the
requests of Algorithm 2 are published in the odometry frame, which the robot knows; and only
when the user enables ``publish_goals`` (a localization node does not command the robot).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

from symloc.errors import ConfigurationError
from symloc.ros.params import NodeParams

__all__ = ["rclpy_available", "run_node"]


def rclpy_available() -> bool:
    """True when rclpy and the message packages import (``pip install '.[ros]'`` in symloc's checkout)."""
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
            "symloc ros node needs rclpy and the ROS message packages: pip install '.[ros]' in symloc's checkout"
        )


def run_node(
    params_path: str | Path | None = None,
    ros_args: Sequence[str] = (),
    *,
    node_name: str | None = None,
    autostart: bool = False,
) -> int:
    """Run the node until Ctrl-C (``symloc ros node``); returns the exit code.

    The node is the lifecycle node :class:`symloc.ros.lifecycle.LocalizationNode` (named
    ``amcl`` unless ``node_name`` says otherwise); ``params_path`` is a symloc or nav2 params
    file whose block for the node (or a ``symloc:`` block) gives the parameters' defaults,
    ``ros_args`` (``--ros-args --params-file nav2_params.yaml -p ...``) override them.
    ``autostart`` configures and activates it at once (nav2's ``autostart_node``); otherwise
    nav2's lifecycle manager (or ``ros2 lifecycle set``) does.
    """
    _require_rclpy()
    import rclpy
    from rclpy.executors import ExternalShutdownException

    from symloc.ros.lifecycle import DEFAULT_NODE_NAME, LocalizationNode

    name = node_name or DEFAULT_NODE_NAME
    params = None
    if params_path is not None:
        params = _read_params(params_path, name)
    args = [sys.argv[0], *ros_args]
    rclpy.init(args=args)
    node = LocalizationNode(name, params=params, cli_args=list(ros_args))
    if autostart:
        node.autostart()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return 0


def _read_params(path: str | Path, node_name: str) -> NodeParams:
    """A params file's block for ``node_name`` (nav2's flat names; an unknown name is warned
    about on stderr and ignored, as at configure) or symloc's ``symloc:`` block (nested
    ``amcl:``, ``localizer:``, ``symmetry:``)."""
    from symloc.ros.nav2_params import node_params_from_ros, read_params_block

    def warn(line: str) -> None:  # as the node's configure: unknown names are ignored
        print(f"warning: {path}: {line}", file=sys.stderr)

    try:
        return node_params_from_ros(read_params_block(path, node_name), on_unknown=warn)
    except ConfigurationError as err:
        if node_name == "symloc" or "no block for node" not in str(err):
            raise
    return NodeParams.from_yaml(path, node_name="symloc")
