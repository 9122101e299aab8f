"""Run the localizer over a recorded bag (``symloc replay``).

The bag's messages go through :class:`symloc.ros.core.NodeCore` (the ROS node's own logic) in
record order: odometry, images and maps are buffered, and every scan is one localizer step with
the odometry at its stamp and, when the localizer asked for one, the newest image. The result is
the status, the earned pose and the tracker's best estimate at every scan (``symloc replay``
writes the earned poses and every scan's estimate as TUM trajectories).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import DataFormatError
from symloc.grid import OccupancyGrid
from symloc.io.rosbag import BagTopics, bag_topics, read_bag
from symloc.io.tum import TrajectoryPoint
from symloc.localizer import Estimate
from symloc.ros.assemble import check_files
from symloc.ros.core import LocalizerFactory, NodeCore
from symloc.ros.pairing import OdometryBuffer
from symloc.ros.params import NodeParams

__all__ = ["ReplayResult", "build_map_from_bag", "replay_bag", "scans_with_odometry"]

FloatArray = NDArray[np.float64]


@dataclass
class ReplayResult:
    """The localizer's answers over a bag.

    ``trajectory`` one point per scan used; ``truth`` (T, 4) t, x, y, theta from the bag's
    ground-truth topic (empty if none); ``grid`` the map used; ``final`` the last estimate;
    ``dropped`` messages dropped per reason; ``steps`` the localizer's log.
    """

    trajectory: list[TrajectoryPoint]
    truth: FloatArray
    grid: OccupancyGrid | None
    final: Estimate | None
    dropped: dict[str, int] = field(default_factory=dict)
    received: dict[str, int] = field(default_factory=dict)
    steps: list[str] = field(default_factory=list)
    particles: FloatArray | None = None


def replay_bag(
    path: str | Path,
    params: NodeParams,
    *,
    grid: OccupancyGrid | None = None,
    topics: BagTopics | None = None,
    factory: LocalizerFactory | None = None,
    warn: Callable[[str], object] | None = None,
    progress: bool = False,
) -> ReplayResult:
    """Replay ``path`` through the node logic; ``grid`` overrides the bag's map topic.

    Malformed messages are skipped and counted (``dropped["<topic>: malformed in bag"]``).

    Raises
    ------
    ConfigurationError
        The visual map or vocabulary the parameters name cannot be used
        (:func:`symloc.ros.assemble.check_files`).
    """
    if factory is None:
        check_files(params)  # a bad visual map or vocabulary: one clear error, not 0 poses
    core = NodeCore(params, factory=factory, warn=warn)
    if grid is not None:
        core.set_map(grid)
    bag_dropped: Counter[str] = Counter()
    truth: list[list[float]] = []
    trajectory: list[TrajectoryPoint] = []
    total = None
    if progress:
        total = sum(n for _, n in bag_topics(path).values())
    messages: Any = read_bag(path, topics=topics, on_error="skip", dropped=bag_dropped)
    if progress:
        from tqdm import tqdm

        messages = tqdm(messages, total=total, desc="replay", unit="msg")
    for m in messages:
        if m.kind == "scan":
            out = core.add_scan(m.value)
            if out.used:
                est = out.estimate
                trajectory.append(
                    TrajectoryPoint(
                        m.stamp, est.status.value, est.pose, out.best_estimate, est.reason
                    )
                )
        elif m.kind == "odom":
            core.add_odometry(m.value)
        elif m.kind == "image":
            core.add_image(m.value, m.stamp)
        elif m.kind == "map":
            if grid is None:
                core.set_map(m.value)
        elif m.kind == "truth":
            truth.append([m.stamp, *m.value.pose])
        elif m.kind == "initialpose":
            pose, cov = m.value
            core.set_initial_pose(pose, cov)
    store = getattr(core.localizer, "places", None)
    if store is not None and hasattr(store, "visual_map"):
        store.visual_map.close()
    dropped = dict(core.dropped)
    for topic, n in bag_dropped.items():
        dropped[f"{topic}: malformed in bag"] = n
    return ReplayResult(
        trajectory=trajectory,
        truth=np.array(truth).reshape(-1, 4),
        grid=core.grid,
        final=core.last.estimate if core.last is not None else None,
        dropped=dropped,
        received=dict(core.received),
        steps=list(getattr(core.localizer, "log", [])),
        particles=core._particles() if core.localizer is not None else None,
    )


def scans_with_odometry(
    path: str | Path, *, topics: BagTopics | None = None, transform_tolerance: float = 1.0
) -> tuple[list[Any], FloatArray, dict[str, int]]:
    """The bag's scans and the odometry pose (N, 3) at each scan's stamp (interpolated).

    Scans without odometry close enough in time are left out and counted in the returned
    ``dropped`` dict (reason -> count), as the node does.
    """
    buf = OdometryBuffer()
    scans: list[Any] = []
    odom: list[FloatArray] = []
    dropped: Counter[str] = Counter()
    for m in read_bag(path, topics=topics, on_error="skip", dropped=dropped):
        if m.kind == "odom":
            if not buf.add(m.value, max_age=60.0):
                dropped["odom: stamp went backwards"] += 1
        elif m.kind == "scan":
            reading = buf.at(m.stamp, transform_tolerance)
            if isinstance(reading, str):
                dropped[f"scan: {reading}"] += 1
                continue
            scans.append(m.value)
            odom.append(np.asarray(reading.pose))
    return scans, np.asarray(odom, dtype=np.float64).reshape(-1, 3), dict(dropped)


def build_map_from_bag(
    path: str | Path, *, topics: BagTopics | None = None, slam_params: Any = None
) -> Any:
    """Build the occupancy grid from a bag's scans and odometry with symloc's SLAM.

    Returns the :class:`symloc.slam.slam.SlamResult` (``.grid``, ``.poses``).

    Raises
    ------
    DataFormatError
        The bag has fewer than two scans with odometry.
    """
    from symloc.slam.slam import run_slam  # lazy: the SLAM stack (GTSAM) only for --build-map

    scans, odom, dropped = scans_with_odometry(path, topics=topics)
    if len(scans) < 2:
        raise DataFormatError(
            f"bag {path}: expected scans with odometry to build a map, got {len(scans)}"
            f" (dropped: {dropped or 'none'})"
        )
    return run_slam(scans, odom, slam_params, progress=True, desc="slam (bag)")
