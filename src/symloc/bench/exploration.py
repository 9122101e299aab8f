"""A simulated exploration run for mapping: drive a loop along a room's walls, record scans.

The path is the room outline moved inwards by ``margin`` (each vertex along its angle
bisector), traversed ``laps`` times; the simulated differential-drive robot
(:class:`symloc.sim.robot.DiffDriveRobot`) turns on the spot towards each waypoint and drives
straight to it, so its wheel odometry carries the Thrun odometry noise of its ``alphas``. A
scan is simulated (:func:`symloc.sim.lidar.simulate_scan`, the preset's data-sheet noise)
every ``scan_period`` seconds, with the true pose and the noisy odometry at that instant.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from symloc._checks import as_rng, check_positive
from symloc.errors import ConfigurationError, WorldError
from symloc.geometry import angle_diff
from symloc.scan import LaserScan
from symloc.sim.free_space import FreeSpace
from symloc.sim.lidar import PAPER_15M, LidarPreset, simulate_scan
from symloc.sim.odometry_noise import DEFAULT_ALPHAS
from symloc.sim.robot import DiffDriveRobot, OdometryNoise, RobotConfig
from symloc.sim.rooms import Room

__all__ = [
    "ExplorationRun",
    "coverage_stops",
    "exploration_path",
    "free_route",
    "simulate_exploration",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ExplorationRun:
    """Recorded run: ``scans`` (N), true poses ``truth`` (N, 3), odometry ``odometry`` (N, 3),
    ``stamps`` (N,) [s]."""

    scans: list[LaserScan]
    truth: FloatArray
    odometry: FloatArray
    stamps: FloatArray

    @property
    def duration(self) -> float:
        """Simulated time from the first to the last scan [s]."""
        return float(self.stamps[-1] - self.stamps[0]) if self.stamps.size > 1 else 0.0


def exploration_path(room: Room, margin: float = 0.5) -> FloatArray:
    """Waypoints ``(V, 2)`` [m]: the room outline moved inwards by ``margin``.

    Raises
    ------
    WorldError
        The inset path leaves the room or passes closer than ``margin / 2`` to an obstacle.
    """
    m = check_positive(margin, "margin")
    v = np.asarray(room.boundary, dtype=np.float64)
    prev = np.roll(v, 1, axis=0)
    nxt = np.roll(v, -1, axis=0)
    e1 = v - prev
    e2 = nxt - v
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 /= np.linalg.norm(e2, axis=1, keepdims=True)
    # inward normals of a counter-clockwise outline point left of each edge
    n1 = np.column_stack([-e1[:, 1], e1[:, 0]])
    n2 = np.column_stack([-e2[:, 1], e2[:, 0]])
    bis = n1 + n2
    norm = np.linalg.norm(bis, axis=1, keepdims=True)
    bis = bis / np.where(norm > 1e-12, norm, 1.0)
    cos_half = np.maximum(np.sum(bis * n1, axis=1, keepdims=True), 0.2)
    path = v + bis * (m / cos_half)
    if room.kind == "circle" or v.shape[0] > 32:  # smooth outlines: keep every 8th vertex
        path = path[:: max(1, v.shape[0] // 16)]
    if not np.all(room.contains(path)):
        raise WorldError(f"exploration_path: margin {m} m puts the path outside room {room.name!r}")
    return np.asarray(path, dtype=np.float64)


def coverage_stops(
    room: Room,
    covered: FloatArray,
    *,
    reach: float,
    clearance: float,
    start: FloatArray | None = None,
) -> FloatArray:
    """Stops ``(S, 2)`` [m] that bring a mapping trip within ``reach`` [m] of every place of
    the room a robot of radius ``clearance`` [m] can reach from where it drove.

    ``covered`` ``(P, 2)`` [m] is where the trip already drove (the lap along the walls). The
    stops are chosen greedily, each the free cell farthest from the trip and the stops so far
    (the farthest-point rule of the k-centre problem), until none is farther than ``reach``;
    only cells of the free-space components the trip drove in count. They are returned in
    nearest-neighbour order from ``start`` (default the last point of ``covered``). A lap
    along the walls leaves a large room's middle metres from any keyframe; a robot that stops
    at these and looks around leaves no reachable place farther than ``reach`` from keyframes
    facing every way.
    """
    r = check_positive(reach, "reach")
    done = np.asarray(covered, dtype=np.float64).reshape(-1, 2)
    if done.shape[0] == 0:
        return np.zeros((0, 2))
    free = room.free_space(clearance)
    h, w = free.free.shape
    row, col = free.cells(done)
    inside = (row >= 0) & (row < h) & (col >= 0) & (col < w)
    labels = np.unique(free.labels[row[inside], col[inside]])
    labels = labels[labels > 0]
    rr, cc = np.nonzero(free.free & np.isin(free.labels, labels))
    if rr.size == 0:
        return np.zeros((0, 2))
    cells = free.origin + (np.column_stack([cc, rr]).astype(np.float64) + 0.5) * free.resolution
    gap, _ = cKDTree(done).query(cells)
    chosen: list[int] = []
    while True:
        k = int(np.argmax(gap))
        if gap[k] <= r:
            break
        chosen.append(k)
        gap = np.minimum(gap, np.hypot(*(cells - cells[k]).T))
    pts = cells[chosen]
    here = np.asarray(start, dtype=np.float64)[:2] if start is not None else done[-1]
    left = list(range(pts.shape[0]))
    order: list[int] = []
    while left:
        k = min(left, key=lambda i: float(np.hypot(*(pts[i] - here))))
        order.append(k)
        left.remove(k)
        here = pts[k]
    return np.asarray(pts[order], dtype=np.float64).reshape(-1, 2)


def _line_free(free: FreeSpace, a: FloatArray, b: FloatArray) -> bool:
    """Whether every cell the segment ``a -> b`` [m] crosses (sampled at half a cell) is free."""
    n = max(2, math.ceil(float(np.hypot(*(b - a))) / (0.5 * free.resolution)) + 1)
    t = np.linspace(0.0, 1.0, n)[:, None]
    row, col = free.cells(a + t * (b - a))
    h, w = free.free.shape
    inside = (row >= 0) & (row < h) & (col >= 0) & (col < w)
    return bool(np.all(inside) and np.all(free.free[row, col]))


def free_route(room: Room, clearance: float) -> Callable[[FloatArray, FloatArray], FloatArray]:
    """A route planner through ``room`` for a robot kept ``clearance`` [m] from every obstacle.

    Returns ``route(start, goal)``: waypoints ``(K, 2)`` [m] ending at ``goal`` (``start`` not
    included), ``(1, 2)`` when the straight segment is clear, the corners of the shortest
    8-connected path through the free cells (:func:`skimage.graph.route_through_array`,
    shortened by line of sight) when it is not, and ``(0, 2)`` when no free path joins them.
    A start or goal in a blocked cell (a waypoint inside furniture, a robot scraping a wall) is
    moved to the nearest free cell first, which then also ends the route.

    The teleoperator of a mapping trip steers around what stands in the way; driving straight
    at each waypoint left the far side of furniture, and most of a corridor past a box,
    unmapped.
    """
    from scipy import ndimage
    from skimage.graph import route_through_array

    free = room.free_space(clearance)
    grid = free.free
    h, w = grid.shape
    # index of the nearest free cell, for starts and goals in blocked cells
    _, (near_r, near_c) = ndimage.distance_transform_edt(~grid, return_indices=True)
    cost = np.where(grid, 1.0, np.inf)

    def centre(r: int, c: int) -> FloatArray:
        return free.origin + (np.array([c, r], dtype=np.float64) + 0.5) * free.resolution

    def snap(p: FloatArray) -> tuple[int, int]:
        row, col = free.cells(p[None])
        r = int(np.clip(row[0], 0, h - 1))
        c = int(np.clip(col[0], 0, w - 1))
        return int(near_r[r, c]), int(near_c[r, c])

    def route(start: FloatArray, goal: FloatArray) -> FloatArray:
        a = np.asarray(start, dtype=np.float64)[:2]
        g = np.asarray(goal, dtype=np.float64)[:2]
        if not grid.any():
            return np.zeros((0, 2))
        if _line_free(free, a, g):
            return g[None].copy()
        ra, ca = snap(a)
        rg, cg = snap(g)
        if free.labels[ra, ca] != free.labels[rg, cg]:
            return np.zeros((0, 2))
        cells, _ = route_through_array(cost, (ra, ca), (rg, cg), fully_connected=True)  # type: ignore[no-untyped-call]
        pts = np.array([centre(r, c) for r, c in cells])
        end = g if _line_free(free, pts[-1], g) else pts[-1]
        pts = np.vstack([pts, end[None]])
        # line-of-sight shortening: from each kept point, jump to the farthest visible one
        out: list[FloatArray] = []
        here = a
        if not _line_free(free, a, pts[0]):  # the robot stands in a blocked cell: out first
            here = pts[0]
            out.append(here)
        i = 0
        while i < pts.shape[0] - 1:
            j = pts.shape[0] - 1
            while j > i + 1 and not _line_free(free, here, pts[j]):
                j -= 1
            out.append(pts[j])
            here, i = pts[j], j
        return np.asarray(out, dtype=np.float64)

    return route


def simulate_exploration(
    room: Room,
    *,
    preset: LidarPreset = PAPER_15M,
    alphas: tuple[float, float, float, float] = DEFAULT_ALPHAS,
    margin: float = 0.5,
    laps: float = 1.3,
    speed: float = 0.3,
    turn_rate: float = 0.8,
    scan_period: float = 0.4,
    rng: np.random.Generator | int | None = None,
) -> ExplorationRun:
    """Drive ``laps`` times around :func:`exploration_path` and record scans.

    Parameters
    ----------
    room : Room
    preset : LidarPreset
        Simulated scanner (default the paper's 15 m, 360-beam Gazebo scanner).
    alphas : tuple of 4 floats
        Odometry noise alpha1..alpha4.
    margin : float
        Distance of the path from the walls [m].
    laps : float
        Number of loops (> 1 revisits the start, so the SLAM back end can close the loop).
    speed, turn_rate : float
        Driving speed [m/s] and turning rate [rad/s].
    scan_period : float
        Time between recorded scans [s].
    rng : Generator, int or None
        Odometry and range noise.
    """
    if not laps > 0:
        raise ConfigurationError(f"laps: expected > 0, got {laps}")
    check_positive(speed, "speed")
    check_positive(turn_rate, "turn_rate")
    period = check_positive(scan_period, "scan_period")
    gen = as_rng(rng)
    path = exploration_path(room, margin)
    n_wp = path.shape[0]
    total_wp = math.ceil(laps * n_wp) + 1
    targets = np.array([path[k % n_wp] for k in range(total_wp)])
    first_heading = math.atan2(targets[1, 1] - targets[0, 1], targets[1, 0] - targets[0, 0])
    start = np.array([targets[0, 0], targets[0, 1], first_heading])
    cfg = RobotConfig(
        noise=OdometryNoise(*alphas), max_v=max(0.7, speed), max_w=max(3.0, turn_rate)
    )
    robot = DiffDriveRobot(start, cfg, gen, world=room.world, odom_origin=start)
    dt = 0.05
    scans: list[LaserScan] = []
    truth: list[FloatArray] = []
    odom: list[FloatArray] = []
    stamps: list[float] = []
    next_scan = 0.0

    def _record() -> None:
        nonlocal next_scan
        while robot.time + 1e-9 >= next_scan:
            pose = robot.pose
            scans.append(simulate_scan(room.world, pose, preset, gen, stamp=robot.time))
            truth.append(pose)
            odom.append(robot.odometry().pose.copy())
            stamps.append(robot.time)
            next_scan += period

    _record()
    for k in range(1, total_wp):
        goal = targets[k]
        pose = robot.pose
        heading = math.atan2(goal[1] - pose[1], goal[0] - pose[0])
        turn = float(angle_diff(heading, pose[2]))
        steps = max(1, math.ceil(abs(turn) / (turn_rate * dt)))
        for _ in range(steps):
            robot.step(0.0, turn / (steps * dt), dt)
            _record()
        dist = float(np.hypot(*(goal - robot.pose[:2])))
        steps = max(1, math.ceil(dist / (speed * dt)))
        for _ in range(steps):
            if not robot.step(dist / (steps * dt), 0.0, dt):
                raise WorldError(f"simulate_exploration: the path collides in room {room.name!r}")
            _record()
    return ExplorationRun(scans, np.array(truth), np.array(odom), np.array(stamps))
