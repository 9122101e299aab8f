"""Memory across map changes: does RSS return to its level after the node's map is replaced?

    PYTHONPATH=src python3 benchmarks/map_change_memory.py [--rebuilds 150] [--scans 20]
        [--node] [--resolution 0.05] [--collect] [--objects] [--tracemalloc] [--json out.json]

:class:`symloc.ros.core.NodeCore` (or, with ``--node``, the ROS 2 lifecycle node in-process,
rclpy messages through its own callbacks) with the real localizer (nav2 AMCL defaults) tracks
a robot circling in an L-shaped room; every ``--scans`` scans (2 s at 10 Hz) a new map arrives
on the map topic: the same room with a 2 x 2-cell box somewhere else, so each map is new and the
localizer is rebuilt on it (issue 31 measured +0.33 MB of RSS per rebuild over 150 rebuilds,
still rising). Not paced in real time. Prints RSS [MB] every 10 rebuilds with the number of
replaced localizers still alive (weak references), the slope of RSS against the rebuild
number over the second half (MB per rebuild), and with ``--objects`` / ``--tracemalloc`` what
grew between the middle and the end.

Measured (2-core machine, shared): 106 x 106 map, 150 rebuilds: NodeCore 249.1 -> 249.8 MB
(+0.005 MB per rebuild), the lifecycle node 294.0 -> 294.7 MB (+0.003), code before issue 31's
work (be414ad^, 100 rebuilds) +0.015; replaced localizers are freed at once (0 alive). 530 x
530 map (``--resolution 0.01``), 200 rebuilds: RSS moves in a band of 275-290 MB without a
trend; with ``MALLOC_MMAP_THRESHOLD_=131072`` (glibc's dynamic mmap threshold off) it stays at
266 MB, at about a third more CPU per scan; ``malloc_trim(0)`` after the change did not bring it
back. The issue's +0.33 MB per rebuild was not reproduced in-process.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import os
import sys
import time
import tracemalloc
import weakref
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np


def rss_mb() -> float:
    """Current resident set size [MB] (Linux /proc)."""
    with open(f"/proc/{os.getpid()}/statm") as fh:
        pages = int(fh.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


class _CoreFeed:
    """Messages into NodeCore (the node's logic without ROS)."""

    def __init__(self, core: Any, map_message: Callable[[Any, float], Any]) -> None:
        self.core = core
        self._map_message = map_message

    def odometry(self, reading: Any) -> None:
        self.core.add_odometry(reading)

    def scan(self, scan: Any) -> str:
        return _status(self.core.add_scan(scan))

    def map(self, grid: Any, stamp: float) -> None:
        self.core.on_map(self._map_message(grid, stamp))

    def close(self) -> None:
        pass


def _core_feed(base: Any, truth: Callable[[float], Any], map_message: Any) -> _CoreFeed:
    from symloc.odometry import OdometryReading
    from symloc.ros.core import NodeCore
    from symloc.ros.params import NodeParams

    core = NodeCore(NodeParams(laser_frame_id="laser"))
    core.set_map(base)
    core.add_odometry(OdometryReading(truth(0.0), 0.0))
    core.set_initial_pose(truth(0.0), np.diag([0.01, 0.01, 0.01]))
    return _CoreFeed(core, map_message)


class _NodeFeed:
    """rclpy messages into the lifecycle node's own callbacks (configured and active)."""

    def __init__(self, node: Any, context: Any, grid_to_fields: Any) -> None:
        from geometry_msgs.msg import PoseWithCovarianceStamped
        from nav_msgs.msg import OccupancyGrid as GridMsg
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import LaserScan as ScanMsg

        self.node = node
        self.core = node.core
        self.context = context
        self._types = (Odometry, ScanMsg, GridMsg, PoseWithCovarianceStamped)
        self._grid_to_fields = grid_to_fields
        self._on_map = node._guard(node.core.on_map)

    def odometry(self, reading: Any) -> None:
        from symloc.msgs import build_rclpy, odometry_to_fields

        self.node._on_odom_msg(build_rclpy(self._types[0], odometry_to_fields(reading)))

    def scan(self, scan: Any) -> str:
        from symloc.msgs import build_rclpy, scan_to_fields

        self.node._on_scan(build_rclpy(self._types[1], scan_to_fields(scan)))
        return _status(getattr(self.core, "last", None))

    def map(self, grid: Any, stamp: float) -> None:
        from symloc.msgs import build_rclpy

        self._on_map(build_rclpy(self._types[2], self._grid_to_fields(grid, stamp=stamp)))

    def close(self) -> None:
        import rclpy

        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


def _node_feed(
    base: Any, t_base: float, truth: Callable[[float], Any], grid_to_fields: Any
) -> _NodeFeed:
    import random

    import rclpy
    from rclpy.context import Context

    from symloc.msgs import build_rclpy, pose_with_covariance_to_fields
    from symloc.ros.lifecycle import LocalizationNode
    from symloc.ros.params import NodeParams

    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    context = Context()
    rclpy.init(context=context, domain_id=random.randint(101, 200))
    params = NodeParams(laser_frame_id="laser", odom_source="topic", laser_pose_source="parameters")
    node = LocalizationNode(context=context, params=params)
    assert node.trigger_configure().name == "SUCCESS"
    assert node.trigger_activate().name == "SUCCESS"
    feed = _NodeFeed(node, context, grid_to_fields)
    feed.map(base, t_base)
    from symloc.odometry import OdometryReading

    feed.odometry(OdometryReading(truth(0.0), t_base))
    from geometry_msgs.msg import PoseWithCovarianceStamped

    cov = np.diag([0.01, 0.01, 0.01])
    fields = pose_with_covariance_to_fields(truth(0.0), cov, stamp=t_base)
    node._on_initialpose(build_rclpy(PoseWithCovarianceStamped, fields))
    return feed


def moved_box_map(base: Any, k: int) -> Any:
    """``base`` (an OccupancyGrid) with a 2 x 2-cell box on the ``k``-th free cell of a stride.

    A new map for each ``k`` (the same room, a box somewhere else), so a node that receives it
    rebuilds its localizer. Shared with ``soak_node.py --map-change``.
    """
    d = base.data.copy()
    free = np.argwhere(d == 0)
    r, c = free[(k * 7919) % len(free)]
    d[r : r + 2, c : c + 2] = 100
    return type(base)(d, base.resolution, base.origin)


def _object_counts() -> Counter[str]:
    """Live objects tracked by the garbage collector, by type name."""
    gc.collect()
    return Counter(type(o).__name__ for o in gc.get_objects())


def _status(out: Any) -> str:
    """The localizer status of one scan's outputs (its diagnostic's ``status`` value)."""
    if out is None:
        return "none"
    entries = out.status.get("status", []) if isinstance(out.status, dict) else []
    values = entries[0].get("values", []) if entries else []
    return next((v["value"] for v in values if v.get("key") == "status"), "?")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rebuilds", type=int, default=150)
    ap.add_argument("--scans", type=int, default=20, help="scans between map changes")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--resolution", type=float, default=0.05, help="map cell size [m] (0.01: 530 x 530)"
    )
    ap.add_argument("--tracemalloc", action="store_true")
    ap.add_argument(
        "--collect",
        action="store_true",
        help="run the garbage collector after every map change (as a node does not)",
    )
    ap.add_argument(
        "--objects", action="store_true", help="print the object types that grew (gc, cheap)"
    )
    ap.add_argument(
        "--node",
        action="store_true",
        help="drive the ROS 2 lifecycle node in-process (rclpy messages through its callbacks,"
        " its publishers live; no executor) instead of NodeCore alone",
    )
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)

    from symloc.msgs import grid_to_fields
    from symloc.odometry import OdometryReading
    from symloc.sim.lidar import PRESETS, simulate_scan
    from symloc.sim.rasterize import world_to_grid
    from symloc.sim.rooms import build_room

    rng = np.random.default_rng(args.seed)
    room = build_room("l_shaped", 3.0, lab=False)
    base = world_to_grid(room.world, args.resolution)
    preset = PRESETS["rplidar_a2"]
    centre = np.asarray(room.center, float)
    rate = 10.0

    def truth(t: float) -> np.ndarray:
        a = 0.2 * t
        return np.array(
            [centre[0] + 0.4 * math.cos(a), centre[1] + 0.4 * math.sin(a), a + math.pi / 2]
        )

    def map_message(grid: Any, stamp: float) -> Any:
        """The map as it arrives on the topic (a nav_msgs/OccupancyGrid look-alike)."""
        from types import SimpleNamespace as NS  # noqa: N814 - short, read as a message

        f = grid_to_fields(grid, stamp=stamp)
        info = f["info"]
        o = info["origin"]
        origin = NS(position=NS(**o["position"]), orientation=NS(**o["orientation"]))
        header = NS(stamp=NS(**f["header"]["stamp"]), frame_id=f["header"]["frame_id"])
        return NS(
            header=header,
            info=NS(
                width=info["width"],
                height=info["height"],
                resolution=info["resolution"],
                origin=origin,
            ),
            data=f["data"],
        )

    t_base = time.time() if args.node else 0.0
    if args.node:
        feed = _node_feed(base, t_base, truth, grid_to_fields)
    else:
        feed = _core_feed(base, truth, map_message)
    core = feed.core
    t = 0.0
    old: list[weakref.ref[Any]] = []
    statuses: dict[str, int] = {}
    rows: list[tuple[int, float]] = []
    snap_mid = None
    objects_mid: Counter[str] = Counter()
    if args.tracemalloc:
        tracemalloc.start(25)
    print(f"# map changes: {args.rebuilds} rebuilds, {args.scans} scans between, pid {os.getpid()}")
    for k in range(args.rebuilds + 1):
        for _ in range(args.scans):
            t += 1.0 / rate
            for j in range(5):
                tj = t - 1.0 / rate + (j + 1) / (5 * rate)
                feed.odometry(OdometryReading(truth(tj), t_base + tj))
            scan = simulate_scan(room.world, truth(t), preset, rng, stamp=t_base + t)
            status = feed.scan(scan)
            statuses[status] = statuses.get(status, 0) + 1
        if k < args.rebuilds:
            old.append(weakref.ref(core.localizer))
            feed.map(moved_box_map(base, k), t_base + t)
            assert getattr(core, "map_refused", "") == "", core.map_refused
        if args.collect:
            gc.collect()
        rows.append((k, rss_mb()))
        if k % 10 == 0:
            alive = sum(r() is not None for r in old)
            print(
                f"rebuild {k:4d}  RSS {rows[-1][1]:7.1f} MB  replaced localizers still alive"
                f" {alive}",
                flush=True,
            )
        if args.tracemalloc and k == args.rebuilds // 2:
            snap_mid = tracemalloc.take_snapshot()
        if args.objects and k == args.rebuilds // 2:
            objects_mid = _object_counts()
    half = [(k, m) for k, m in rows if k >= args.rebuilds // 2]
    ks = np.array([k for k, _ in half], float)
    ms = np.array([m for _, m in half])
    slope = float(np.polyfit(ks, ms, 1)[0]) if len(half) > 2 else float("nan")
    first = rows[min(10, len(rows) - 1)][1]
    print(f"scan statuses: {statuses}")
    print(
        f"RSS after 10 rebuilds {first:.1f} MB, at the end {rows[-1][1]:.1f} MB;"
        f" slope over the second half {slope:+.4f} MB per rebuild"
    )
    if args.tracemalloc and snap_mid is not None:
        end = tracemalloc.take_snapshot()
        for stat in end.compare_to(snap_mid, "traceback")[:8]:
            print(f"{stat.size_diff / 1024:+9.1f} KiB {stat.count_diff:+7d} blocks")
            for line in stat.traceback.format()[-6:]:
                print("    " + line)
    if args.objects:
        grew = _object_counts()
        grew.subtract(objects_mid)
        print("objects that grew over the second half:", grew.most_common(8))
    feed.close()
    if args.json is not None:
        args.json.write_text(json.dumps({"rss_mb": rows, "slope_mb_per_rebuild": slope}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
