"""Scans a user brings to the symmetry judgement: a CARMEN log, a ROS bag, a simulated room.

Each loader returns a :class:`SourcedScan` (the scan plus where it came from and, for a
simulated room, the ground truth in the sensor frame) and raises a :class:`SymlocError` with a
message naming the bad input, never a bare NumPy / IO error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from symloc._checks import as_rng
from symloc.errors import ConfigurationError, DataFormatError
from symloc.io.carmen import read_carmen
from symloc.io.rosbag import BagTopics, bag_topics, read_bag, resolve_bag_path
from symloc.scan import LaserScan
from symloc.sim.lidar import PRESETS, simulate_scan
from symloc.sim.rooms import ROOM_NAMES, build_room, points_in_polygon
from symloc.symmetry.config import SymmetryConfig

__all__ = ["SourcedScan", "bag_scan", "carmen_scan", "room_scan"]


@dataclass(frozen=True, eq=False)
class SourcedScan:
    """A scan and its origin.

    Attributes
    ----------
    scan : LaserScan
    source : str
        Human-readable origin (file and index, or room and pose).
    index : int
        Index of the scan in its log or topic (0 for a simulated room).
    count : int
        Number of scans in the log or topic (1 for a simulated room; -1 when not counted).
    truth : dict
        Simulated room only: ``kind``, ``order`` (the room's true rotational symmetry order as
        seen by the lidar; 0 means continuous), ``center`` (2,) in the sensor frame [m],
        ``gv_distance`` [m].
    sigma : float or None
        Range noise [m] of the sensor when known (simulated presets), else None.
    sigma_relative : float
        Relative range noise of the sensor when known, else 0.
    """

    scan: LaserScan
    source: str
    index: int = 0
    count: int = 1
    truth: dict[str, Any] = field(default_factory=dict)
    sigma: float | None = None
    sigma_relative: float = 0.0


def _check_index(index: int) -> int:
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
        raise ConfigurationError(f"index: expected an integer, got {index!r}")
    return int(index)


def carmen_scan(path: str | Path, index: int = 0) -> SourcedScan:
    """Scan ``index`` (FLASER message, 0-based; negative counts from the end) of a CARMEN log.

    Raises
    ------
    DataFormatError
        The file does not exist, is malformed, has no FLASER scan, or the index is out of range.
    ConfigurationError
        The index is not an integer.
    """

    idx = _check_index(index)
    p = Path(path)
    if not p.is_file():
        raise DataFormatError(f"carmen: log file not found: {p}")
    try:
        log = read_carmen(p)
    except (UnicodeError, OSError, EOFError) as err:
        raise DataFormatError(f"carmen: cannot read {p}: {err}") from err
    n = len(log.scans)
    if n == 0:
        raise DataFormatError(f"carmen: {p} holds no FLASER scan")
    if not -n <= idx < n:
        raise DataFormatError(
            f"index: expected -{n} <= N < {n} for {p.name} ({n} scans), got {idx}"
        )
    idx %= n
    return SourcedScan(log.scans[idx].scan, f"CARMEN {p.name} scan {idx}", idx, n)


def bag_scan(path: str | Path, topic: str | None = None, index: int = 0) -> SourcedScan:
    """Scan ``index`` (0-based, >= 0) of a sensor_msgs/LaserScan topic of a ROS 1/2 bag.

    Parameters
    ----------
    path : str or Path
        ROS 1 ``.bag``, ROS 2 bag folder, or the ``.db3`` / ``.mcap`` inside one.
    topic : str, optional
        LaserScan topic; default: the first LaserScan topic of the bag.
    index : int
        Which scan message of the topic (>= 0).

    Raises
    ------
    DataFormatError
        Not a bag, no such topic, the topic is not a LaserScan, or fewer scans than the index.
    """

    idx = _check_index(index)
    if idx < 0:
        raise ConfigurationError(f"index: expected >= 0 for a bag topic, got {idx}")
    resolve_bag_path(path)  # clear error for a path that is no bag
    try:
        listing = bag_topics(path)
    except DataFormatError:
        raise
    except Exception as err:  # rosbags raises its own family; present one
        raise DataFormatError(f"bag: cannot open {path}: {err}") from err
    scan_topics = sorted(t for t, (ty, _n) in listing.items() if ty == "sensor_msgs/msg/LaserScan")
    if topic is None:
        if not scan_topics:
            raise DataFormatError(
                f"bag: no sensor_msgs/LaserScan topic in {path}; topics: {sorted(listing)}"
            )
        topic = scan_topics[0]
    count = -1
    for name in (topic, "/" + topic.lstrip("/"), topic.lstrip("/")):
        if name in listing:
            count = int(listing[name][1])
            break
    seen = 0
    for msg in read_bag(path, topics=BagTopics(scan=topic, truth=None)):
        if msg.kind != "scan":
            continue
        if seen == idx:
            return SourcedScan(
                msg.value, f"bag {Path(path).name} {msg.topic} scan {idx}", idx, count
            )
        seen += 1
    raise DataFormatError(
        f"index: expected 0 <= N < {seen} (scans on {topic} in {path}), got {idx}"
    )


def room_scan(
    room: str,
    gv: float,
    pose: ArrayLike,
    *,
    sensor: str = "paper_15m",
    rng: np.random.Generator | int | None = None,
    door: bool = False,
    furniture: int = 0,
) -> SourcedScan:
    """Simulate one scan in a room built by :func:`symloc.sim.rooms.build_room` (no lab).

    Parameters
    ----------
    room : str
        Room name (``square``, ``hexagon``, ``circle``, ``rectangle``, ``hallway``, ...).
    gv : float
        G-V distance [m] (> 0).
    pose : array of shape (3,)
        Robot pose x [m], y [m], heading [deg] in the room frame (room centre at the origin
        for the regular rooms; see :attr:`Room.center`).
    sensor : str
        Lidar preset name (``paper_15m``, ``lds01``, ``rplidar_a2``).
    rng : Generator, int or None
        Range noise and furniture placement.
    door : bool
        Open a door gap in the first wall.
    furniture : int
        Boxes placed in the room.

    Raises
    ------
    ConfigurationError
        Unknown room or sensor, bad G-V distance or pose, or a pose outside the room.
    """

    if room not in ROOM_NAMES:
        raise ConfigurationError(f"room: expected one of {ROOM_NAMES}, got {room!r}")
    if sensor not in PRESETS:
        raise ConfigurationError(f"sensor: expected one of {sorted(PRESETS)}, got {sensor!r}")
    if not (isinstance(gv, (int, float)) and math.isfinite(gv) and gv > 0):
        raise ConfigurationError(f"gv: expected a G-V distance > 0 m, got {gv!r}")
    q = np.asarray(pose, dtype=np.float64).reshape(-1)
    if q.shape != (3,) or not np.all(np.isfinite(q)):
        raise ConfigurationError(f"pose: expected three finite numbers X Y DEG, got {pose!r}")
    gen = as_rng(rng)
    r = build_room(room, float(gv), lab=False, door=door, furniture=furniture, rng=gen)
    if not bool(points_in_polygon(q[:2], r.boundary)[0]):
        lo = r.boundary.min(axis=0)
        hi = r.boundary.max(axis=0)
        raise ConfigurationError(
            f"pose: ({q[0]:g}, {q[1]:g}) m is outside the {room} (G-V {gv:g} m; its outline spans"
            f" x {lo[0]:.2f}..{hi[0]:.2f}, y {lo[1]:.2f}..{hi[1]:.2f} m)"
        )
    pose_rad = np.array([q[0], q[1], math.radians(q[2])])
    preset = PRESETS[sensor]
    scan = simulate_scan(r.world, pose_rad, preset, gen)
    # truth in the sensor frame
    c = np.asarray(r.center, dtype=np.float64)
    s, co = math.sin(pose_rad[2]), math.cos(pose_rad[2])
    d = c - pose_rad[:2]
    center_sensor = np.array([co * d[0] + s * d[1], -s * d[0] + co * d[1]])
    truth = {
        "kind": r.kind,
        "order": int(r.order),
        "center": center_sensor,
        "gv_distance": float(r.gv_distance),
    }

    cfg = SymmetryConfig.from_lidar(preset)
    return SourcedScan(
        scan,
        f"simulated {room} (G-V {gv:g} m, {sensor}) at x {q[0]:g} m, y {q[1]:g} m,"
        f" heading {q[2]:g} deg",
        0,
        1,
        truth,
        cfg.range_sigma,
        cfg.range_sigma_relative,
    )
