"""``symloc ros node --params params.yaml``: the ROS 2 node (needs ``pip install symloc[ros]``)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

__all__ = ["register"]


def register(subparsers: Any) -> None:
    """Add the ``ros`` sub-command group."""
    p: argparse.ArgumentParser = subparsers.add_parser(
        "ros", help="ROS 2 integration (rclpy node)", description="ROS 2 integration."
    )
    sub = p.add_subparsers(dest="ros_command", metavar="COMMAND")
    sub.required = True
    node = sub.add_parser(
        "node",
        help="run the symloc localization node",
        description="Run the symloc node: subscribes scan, odom, map, camera, initialpose;"
        " publishes amcl_pose, particle_cloud, symloc/status, symloc/candidates, goal_pose,"
        " symloc/capture_request. Extra arguments after --ros-args go to rclpy"
        " (e.g. --ros-args -r scan:=/front/scan -r __ns:=/robot1).",
    )
    node.add_argument("--params", type=Path, required=True, help="nav2-style parameters YAML")
    node.add_argument("ros_args", nargs=argparse.REMAINDER, help="--ros-args ... for rclpy")
    node.set_defaults(func=_run_node)
    check = sub.add_parser("check-params", help="validate a parameters YAML and print it")
    check.add_argument("params", type=Path)
    check.set_defaults(func=_check)


def _run_node(args: argparse.Namespace) -> int:
    from symloc.ros.node import run_node

    return run_node(args.params, list(args.ros_args))


def _check(args: argparse.Namespace) -> int:
    from symloc.ros.params import NodeParams

    params = NodeParams.from_yaml(args.params)
    print(params)
    return 0
