"""Driving the localizer's requests in the simulator.

Two loops:

- :func:`go_to_centre`: Algorithm 2 alone (the paper's Table 2): scan, judge (Algorithm 1),
  smooth the centre, command the differential drive, until the controller says ``done``.
- :func:`run_episode`: the full :class:`~symloc.localizer.localizer.Localizer` with a driver that
  carries out its requests (go to the centre, face, rotate, capture an image) and turns on the
  spot when it has nothing to do and the pose is not earned (AMCL integrates a scan only after
  the robot moved).

The robot is anything with a true ``pose`` and ``drive(v, w, dt) -> OdometryReading``
(:class:`Body`); :class:`RobotBody` adapts :class:`symloc.sim.robot.DiffDriveRobot`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import wrap_angle
from symloc.localizer.centering import CenteringConfig, CentreFilter, centering_command
from symloc.localizer.types import Estimate, Request, RequestKind, Status, SymmetryJudge
from symloc.odometry import OdometryReading

__all__ = [
    "Body",
    "CenteringRun",
    "Episode",
    "RobotBody",
    "drive_command",
    "drive_waypoints",
    "go_to_centre",
    "look_around_at",
    "run_episode",
]

FloatArray = NDArray[np.float64]


class Body(Protocol):
    """A simulated differential-drive robot."""

    @property
    def pose(self) -> FloatArray:
        """True pose (3,) in the world frame."""

    @property
    def odom(self) -> OdometryReading:
        """The current odometry reading (odometry frame)."""

    def drive(self, v: float, w: float, dt: float) -> OdometryReading:
        """Move with ``v`` [m/s], ``w`` [rad/s] for ``dt`` [s]; return the noisy odometry."""


class RobotBody:
    """:class:`symloc.sim.robot.DiffDriveRobot` as a :class:`Body`; counts refused motions.

    ``collisions`` counts commands the robot refused because they would touch an obstacle
    (Algorithm 2 must keep it at zero).
    """

    def __init__(self, robot: Any) -> None:
        self.robot = robot
        self.collisions = 0
        #: the last commanded (v [m/s], w [rad/s]) (a spinning lidar's motion skew)
        self.twist = (0.0, 0.0)

    @property
    def pose(self) -> FloatArray:
        return np.asarray(self.robot.pose, dtype=np.float64)

    @property
    def odom(self) -> OdometryReading:
        reading: OdometryReading = self.robot.odometry()
        return reading

    def teleport(self, pose: FloatArray) -> None:
        """Kidnap: move the true pose without odometry noticing."""
        self.robot.teleport(pose)

    def drive(self, v: float, w: float, dt: float) -> OdometryReading:
        cfg = self.robot.config
        v = float(np.clip(v, -cfg.max_v, cfg.max_v))
        w = float(np.clip(w, -cfg.max_w, cfg.max_w))
        self.twist = (v, w)
        if not self.robot.step(v, w, dt):
            self.collisions += 1
        return self.odom


def _scan_middle(scan: Any) -> FloatArray | None:
    """Mean of the valid scan points (2,) in the sensor frame, or None."""
    pts = scan.to_points().points
    if pts.shape[0] == 0:
        return None
    return np.asarray(pts.mean(axis=0), dtype=np.float64)


ScanFn = Callable[[FloatArray], Any]
ImageFn = Callable[[FloatArray], NDArray[np.uint8]]


@dataclass(frozen=True)
class CenteringRun:
    """One run of Algorithm 2.

    ``path`` (T, 3) true poses; ``error`` [m] final distance to the true centre; ``phase`` the
    controller's last phase (``done`` on success); ``heading_error`` [rad] from the facing
    direction given by the caller (NaN if none); ``judged`` scans judged symmetric / ``steps``.
    """

    path: FloatArray
    error: float
    phase: str
    steps: int
    time: float
    distance: float
    judged: int
    heading_error: float = math.nan


def go_to_centre(
    body: Body,
    scan_at: ScanFn,
    judge: SymmetryJudge,
    *,
    true_centre: FloatArray,
    config: CenteringConfig | None = None,
    dt: float = 0.2,
    max_time: float = 120.0,
    explore_time: float = 30.0,
    smoothing: float = 0.5,
    odom_start: OdometryReading | None = None,
    true_facings: FloatArray | None = None,
) -> CenteringRun:
    """Run Algorithm 2 in the simulator until the controller reports ``done`` (or time runs out).

    Parameters
    ----------
    body : Body
    scan_at : callable
        ``scan_at(true_pose) -> LaserScan`` (the simulated lidar with its noise).
    judge : SymmetryJudge
    true_centre : ndarray of shape (2,)
        Ground truth, for the reported error only.
    true_facings : ndarray of shape (D,), optional
        World headings [rad] of the true corner middles, for the reported heading error only.
    explore_time : float
        While no scan has been judged symmetric the robot heads for the middle of what it sees;
        after this long [s] without a symmetric verdict it stops (phase ``"no_symmetry"``).
    """
    cfg = config if config is not None else CenteringConfig()
    filt = CentreFilter(alpha=smoothing)
    odom = odom_start if odom_start is not None else OdometryReading(np.zeros(3))
    path = [body.pose]
    phase = "blocked"
    steps = judged = 0
    distance = 0.0
    facing_odom: float | None = None
    t = 0.0
    while t < max_time:
        if judged == 0 and t >= explore_time:
            phase = "no_symmetry"  # explored without ever seeing a symmetric place
            break
        pose = body.pose
        scan = scan_at(pose)
        verdict = judge(scan)
        if verdict.symmetric and verdict.center is not None:
            judged += 1
            target = filt.update(odom.pose, verdict.center)
        else:
            target = filt.update(odom.pose, None)
        if verdict.symmetric and verdict.facing is not None:
            facing_odom = float(odom.pose[2]) + verdict.facing  # carried along by odometry
        facing = None if facing_odom is None else float(wrap_angle(facing_odom - odom.pose[2]))
        if target is None:
            # no verdict yet (e.g. the far corners are beyond range): head for the middle of
            # what the lidar sees, which lies towards the room's centre, until one arrives
            cmd = centering_command(_scan_middle(scan), None, scan, cfg)
            phase = "explore" if cmd.phase != "blocked" else "blocked"
        else:
            cmd = centering_command(target, facing, scan, cfg)
            phase = cmd.phase
        steps += 1
        if phase == "done":
            break
        before = body.pose
        odom = body.drive(cmd.v, cmd.w, dt)
        distance += float(np.hypot(*(body.pose[:2] - before[:2])))
        path.append(body.pose)
        t += dt
    final = body.pose
    err = float(np.hypot(*(final[:2] - np.asarray(true_centre)[:2])))
    heading_error = math.nan
    if true_facings is not None and len(true_facings):
        heading_error = float(np.min(np.abs(wrap_angle(np.asarray(true_facings) - final[2]))))
    return CenteringRun(
        path=np.array(path),
        error=err,
        phase=phase,
        steps=steps,
        time=t,
        distance=distance,
        judged=judged,
        heading_error=heading_error,
    )


@dataclass
class Episode:
    """The record of one :func:`run_episode`.

    ``estimates`` every output; ``path`` (T, 3) true poses; ``images`` the images the
    localizer asked for, ``image_poses`` the true pose (3,) where each was taken; ``time``
    simulated seconds until the final status; ``distance`` [m] travelled; ``wall_time`` [s] of
    computation.
    """

    estimates: list[Estimate] = field(default_factory=list)
    path: list[FloatArray] = field(default_factory=list)
    images: list[NDArray[np.uint8]] = field(default_factory=list)
    image_poses: list[FloatArray] = field(default_factory=list)
    commands: list[tuple[float, float]] = field(default_factory=list)
    time: float = 0.0
    distance: float = 0.0
    wall_time: float = 0.0
    time_to_final: float = 0.0
    distance_to_final: float = 0.0

    @property
    def final(self) -> Estimate:
        return self.estimates[-1]


def drive_command(
    status: Status,
    request: Request | None,
    scan: Any,
    centering: Any,
    explore_w: float = 0.6,
    travel_speed: float = 0.3,
) -> tuple[float, float]:
    """Velocity (v [m/s], w [rad/s]) carrying out ``request`` (Algorithm 2's controller;
    ``GO_TO`` with it at up to ``travel_speed`` [m/s], the mapping trip's speed).

    Lost with no request: turn on the spot so AMCL sees new scans. Capture: stand still.
    """
    if request is None:
        return (0.0, explore_w) if status is Status.LOST else (0.0, 0.0)
    if request.kind in (RequestKind.GO_TO_CENTRE, RequestKind.GO_TO):
        if request.kind is RequestKind.GO_TO:
            centering = replace(centering, max_linear_speed=travel_speed)
        cmd = centering_command(request.target, None, scan, centering)
        return float(cmd.v), float(cmd.w)
    if request.kind in (RequestKind.FACE_DIRECTION, RequestKind.ROTATE):
        angle = float(request.angle or 0.0)
        w = float(
            np.clip(
                centering.angular_gain * angle,
                -centering.max_angular_speed,
                centering.max_angular_speed,
            )
        )
        return 0.0, w
    return 0.0, 0.0


def drive_waypoints(
    body: Body,
    waypoints: FloatArray,
    *,
    laps: float = 1.0,
    dt: float = 0.1,
    speed: float = 0.3,
    turn_rate: float = 0.8,
    on_step: Callable[[FloatArray], Any] | None = None,
    route: Callable[[FloatArray, FloatArray], FloatArray] | None = None,
) -> int:
    """Drive ``body`` through ``waypoints`` (V, 2) [m], ``laps`` times round, from the nearest.

    Turn on the spot towards each waypoint, then drive straight to it (open loop in the true
    pose); with ``route(position, waypoint)`` (e.g.
    :func:`symloc.bench.exploration.free_route`), through the points ``(K, 2)`` it returns
    instead, each in turn (none: the waypoint cannot be reached), steering at each on the true
    pose as a teleoperator would. ``on_step(true_pose)`` is
    called after every step of ``dt`` [s] (e.g. to record a scan). A waypoint the robot cannot
    reach because a motion is refused (an obstacle) or no route leads there is skipped; returns
    how many were skipped.
    """
    wp = np.asarray(waypoints, dtype=np.float64).reshape(-1, 2)
    if wp.shape[0] == 0:
        return 0
    first = int(np.argmin(np.hypot(*(wp - body.pose[:2]).T)))
    order = [(first + k) % wp.shape[0] for k in range(math.ceil(laps * wp.shape[0]) + 1)]
    return sum(not _reach(body, wp[k], dt, speed, turn_rate, on_step, route) for k in order)


def look_around_at(
    body: Body,
    stops: FloatArray,
    *,
    dt: float = 0.1,
    speed: float = 0.3,
    turn_rate: float = 0.8,
    on_step: Callable[[FloatArray], Any] | None = None,
    route: Callable[[FloatArray, FloatArray], FloatArray] | None = None,
) -> int:
    """Drive ``body`` to each of ``stops`` (S, 2) [m] in turn (through ``route`` as
    :func:`drive_waypoints` does) and turn a full circle on the spot there, so that a camera
    sees the room from there in every direction. The circles alternate anticlockwise and
    clockwise: a gyro's scale error (0.2-1 % for a MEMS unit) over dozens of full turns one
    way would turn the heading by degrees where the laser cannot correct it (a round room);
    turned both ways, it cancels. ``on_step(true_pose)`` after every step of ``dt`` [s].
    Returns how many stops could not be reached (skipped)."""
    skipped = 0
    way = 1.0
    for stop in np.asarray(stops, dtype=np.float64).reshape(-1, 2):
        if not _reach(body, stop, dt, speed, turn_rate, on_step, route):
            skipped += 1
            continue
        for _ in range(math.ceil(2.0 * math.pi / (turn_rate * dt))):
            body.drive(0.0, way * turn_rate, dt)
            if on_step is not None:
                on_step(body.pose)
        way = -way
    return skipped


def _reach(
    body: Body,
    point: FloatArray,
    dt: float,
    speed: float,
    turn_rate: float,
    on_step: Callable[[FloatArray], Any] | None,
    route: Callable[[FloatArray, FloatArray], FloatArray] | None,
) -> bool:
    """Drive ``body`` to ``point`` (2,) [m]: straight at it, or through the points ``route``
    returns, each in turn, steering on the way; False when no route leads there or a motion
    was refused (the rest of the route is then not driven)."""
    via = point[None] if route is None else route(body.pose[:2], point)
    if via.shape[0] == 0:
        return False
    return all(
        _drive_straight(body, goal, dt, speed, turn_rate, on_step, route is not None)
        for goal in via
    )


def _drive_straight(
    body: Body,
    goal: FloatArray,
    dt: float,
    speed: float,
    turn_rate: float,
    on_step: Callable[[FloatArray], Any] | None,
    steer: bool = True,
) -> bool:
    """Turn on the spot towards ``goal`` (2,) [m], then drive to it, turning at each step
    towards it (``steer``; else straight on, open loop); False when a motion was refused (an
    obstacle in the way)."""
    pose = body.pose
    turn = float(wrap_angle(math.atan2(goal[1] - pose[1], goal[0] - pose[0]) - pose[2]))
    for _ in range(max(1, math.ceil(abs(turn) / (turn_rate * dt)))):
        step = float(np.clip(turn, -turn_rate * dt, turn_rate * dt))
        body.drive(0.0, step / dt, dt)
        turn -= step
        if on_step is not None:
            on_step(body.pose)
    dist = float(np.hypot(*(goal - body.pose[:2])))
    # the driver keeps the robot pointed at the goal as it goes (a heading error of a degree
    # puts it 0.7 m off course after 40 m: into the wall of a corridor)
    for _ in range(max(1, math.ceil(1.5 * dist / (speed * dt)))):
        before = body.pose
        left = float(np.hypot(*(goal - before[:2])))
        if left < 1e-3:
            break
        d = min(speed * dt, left)
        off = float(wrap_angle(math.atan2(goal[1] - before[1], goal[0] - before[0]) - before[2]))
        w = float(np.clip(off / dt, -turn_rate, turn_rate)) if steer and left > 0.05 else 0.0
        body.drive(d / dt, w, dt)
        if on_step is not None:
            on_step(body.pose)
        if float(np.hypot(*(body.pose[:2] - before[:2]))) < 1e-9 and d > 1e-9:
            return False  # refused: an obstacle in the way
    return True


def run_episode(
    localizer: Any,
    body: Body,
    scan_at: ScanFn,
    image_at: ImageFn,
    *,
    odom_start: OdometryReading,
    dt: float = 0.2,
    max_time: float = 120.0,
    config: CenteringConfig | None = None,
    explore_w: float = 0.6,
    settle_updates: int = 3,
) -> Episode:
    """Run the localizer with a driver that carries out its requests.

    Stops when the status has been ``tracking`` for ``settle_updates`` updates with no request,
    when it is ``ambiguous`` with no request (nothing more to try), or at ``max_time``.
    """
    cfg = config if config is not None else CenteringConfig()
    ep = Episode()
    odom = odom_start
    image: NDArray[np.uint8] | None = None
    t = 0.0
    calm = 0
    wall0 = time.perf_counter()
    ep.path.append(body.pose)
    while t <= max_time:
        scan = scan_at(body.pose)
        est = localizer.update(odom, scan, image)
        if image is not None:
            ep.images.append(image)
        image = None
        ep.estimates.append(est)
        if est.request is None and est.status in (Status.TRACKING, Status.AMBIGUOUS):
            calm += 1
            if calm == 1:
                ep.time_to_final, ep.distance_to_final = t, ep.distance
            if calm >= settle_updates:
                break
        else:
            calm = 0
        if est.request is not None and est.request.kind is RequestKind.CAPTURE_IMAGE:
            image = image_at(body.pose)
            ep.image_poses.append(body.pose)
            continue
        v, w = drive_command(est.status, est.request, scan, cfg, explore_w)
        before = body.pose
        odom = body.drive(v, w, dt)
        ep.commands.append((v, w))
        ep.distance += float(np.hypot(*(body.pose[:2] - before[:2])))
        ep.path.append(body.pose)
        t += dt
    ep.time = t
    ep.wall_time = time.perf_counter() - wall0
    return ep
