"""Algorithm 2: drive a differential-drive robot to the geometric centre, then face a wall middle.

The controller is a pure function from what the robot senses now to a velocity command: the
centre of the place in the robot's own frame (re-estimated from every scan by Algorithm 1, since
the estimate improves near the centre), the bearing of the middle between two adjacent corners,
and the scan itself for a safety check. It turns on the spot towards the target when the bearing
error is large, drives (forwards or backwards, whichever needs the smaller turn) with a speed
proportional to the distance, stops within ``position_tolerance``, then turns to face the
corner middle and stops within ``facing_tolerance``. It never moves towards a return closer than
``min_clearance`` in the direction of travel (walls and furniture): it reports ``blocked``
instead.

:class:`CentreFilter` smooths the per-scan centre estimates in the odometry frame, so the
controller does not chase sensor noise near the goal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_in_range, check_positive
from symloc.geometry import compose, inverse, wrap_angle
from symloc.scan import LaserScan

__all__ = ["CenteringCommand", "CenteringConfig", "CentreFilter", "centering_command"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class CenteringConfig:
    """Settings of the Algorithm 2 controller.

    Attributes
    ----------
    position_tolerance : stop when the centre is this close [m] (paper Table 2: 5-15 mm).
    facing_tolerance : stop turning when the corner middle is this close in bearing [rad].
    max_linear_speed : [m/s].  max_angular_speed : [rad/s].
    min_linear_speed : the slowest creep near the goal [m/s] (wheels do not move below some speed).
    linear_gain : [1/s] speed = gain x distance.  angular_gain : [1/s] turn rate = gain x bearing.
    heading_gate : turn on the spot while the bearing error is larger than this [rad].
    min_clearance : no motion towards a laser return closer than this [m] (robot radius + margin).
    clearance_half_angle : half-width of the cone checked in the direction of travel [rad].
    """

    position_tolerance: float = 0.005
    facing_tolerance: float = math.radians(1.0)
    max_linear_speed: float = 0.15
    min_linear_speed: float = 0.01
    max_angular_speed: float = 1.0
    linear_gain: float = 0.8
    angular_gain: float = 1.5
    heading_gate: float = math.radians(15.0)
    min_clearance: float = 0.25
    clearance_half_angle: float = math.radians(35.0)

    def __post_init__(self) -> None:
        for name in (
            "position_tolerance",
            "facing_tolerance",
            "max_linear_speed",
            "min_linear_speed",
            "max_angular_speed",
            "linear_gain",
            "angular_gain",
            "min_clearance",
        ):
            check_positive(getattr(self, name), f"CenteringConfig.{name}")
        check_in_range(self.heading_gate, "CenteringConfig.heading_gate", 1e-6, math.pi / 2)
        check_in_range(
            self.clearance_half_angle, "CenteringConfig.clearance_half_angle", 1e-6, math.pi
        )


@dataclass(frozen=True, slots=True)
class CenteringCommand:
    """One velocity command: ``v`` [m/s] forward, ``w`` [rad/s] counter-clockwise.

    ``phase`` is ``"turn"`` (turning towards the centre), ``"drive"``, ``"face"`` (at the centre,
    turning to the corner middle), ``"done"`` or ``"blocked"`` (an obstacle is in the way).
    ``distance`` [m] and ``bearing`` [rad] describe the centre in the robot frame.
    """

    v: float
    w: float
    phase: str
    distance: float
    bearing: float


def _clearance(scan: LaserScan | None, direction: float, half_angle: float) -> float:
    """Nearest valid return [m] within ``half_angle`` of ``direction`` (robot frame)."""
    if scan is None:
        return math.inf
    mask = scan.valid_mask & (np.abs(wrap_angle(scan.angles - direction)) <= half_angle)
    if not np.any(mask):
        return math.inf
    return float(np.min(np.asarray(scan.ranges)[mask]))


def _turn(angle: float, config: CenteringConfig) -> float:
    w = config.angular_gain * angle
    return float(np.clip(w, -config.max_angular_speed, config.max_angular_speed))


def centering_command(
    target: ArrayLike | None,
    facing: float | None,
    scan: LaserScan | None = None,
    config: CenteringConfig | None = None,
) -> CenteringCommand:
    """The next velocity command of Algorithm 2.

    Parameters
    ----------
    target : array_like of shape (2,) or None
        The geometric centre in the robot (base) frame [m]; ``None`` when unknown (the command
        is then a stop with phase ``"blocked"``).
    facing : float or None
        Bearing [rad] of the middle between two adjacent corners in the robot frame; ``None``
        (a circle: any heading will do) skips the facing step.
    scan : LaserScan, optional
        The current scan, for the clearance check.
    config : CenteringConfig, optional

    Returns
    -------
    CenteringCommand
    """
    cfg = config if config is not None else CenteringConfig()
    if target is None:
        return CenteringCommand(0.0, 0.0, "blocked", math.nan, math.nan)
    t = np.asarray(target, dtype=np.float64)
    distance = float(np.hypot(t[0], t[1]))
    bearing = float(math.atan2(t[1], t[0])) if distance > 0 else 0.0
    if distance <= cfg.position_tolerance:
        if facing is None or abs(facing) <= cfg.facing_tolerance:
            return CenteringCommand(0.0, 0.0, "done", distance, bearing)
        return CenteringCommand(0.0, _turn(float(facing), cfg), "face", distance, bearing)
    # drive forwards or backwards, whichever needs the smaller turn
    backwards = abs(bearing) > math.pi / 2
    heading_error = float(wrap_angle(bearing - math.pi)) if backwards else bearing
    travel_dir = math.pi if backwards else 0.0
    if abs(heading_error) > cfg.heading_gate:
        return CenteringCommand(0.0, _turn(heading_error, cfg), "turn", distance, bearing)
    clearance = _clearance(scan, travel_dir, cfg.clearance_half_angle)
    if clearance < cfg.min_clearance:
        return CenteringCommand(0.0, 0.0, "blocked", distance, bearing)
    speed = min(cfg.max_linear_speed, max(cfg.min_linear_speed, cfg.linear_gain * distance))
    # never plan to overshoot into the last clearance margin
    speed = min(speed, max(0.0, clearance - cfg.min_clearance) * cfg.linear_gain + 1e-3)
    v = -speed if backwards else speed
    return CenteringCommand(v, _turn(heading_error, cfg), "drive", distance, bearing)


class CentreFilter:
    """Smooths per-scan centre estimates in the odometry frame.

    Parameters
    ----------
    alpha : float
        Weight of a new estimate in (0, 1]; 1 keeps only the newest.
    reset_distance : float
        A new estimate farther than this [m] from the filtered one replaces it.
    """

    def __init__(self, alpha: float = 0.5, reset_distance: float = 0.3) -> None:
        self.alpha = check_in_range(alpha, "CentreFilter.alpha", 1e-6, 1.0)
        self.reset_distance = check_positive(reset_distance, "CentreFilter.reset_distance")
        self._centre_odom: FloatArray | None = None

    def reset(self) -> None:
        """Forget the filtered centre."""
        self._centre_odom = None

    def update(self, odom_pose: ArrayLike, centre_base: ArrayLike | None) -> FloatArray | None:
        """Blend a new estimate ``centre_base`` (2,) seen from ``odom_pose`` (3,).

        Returns the filtered centre in the base frame (2,), or ``None`` if none is known yet. A
        ``None`` estimate (the judgement failed on this scan) keeps the previous centre, carried
        along by odometry.
        """
        pose = np.asarray(odom_pose, dtype=np.float64)
        if centre_base is not None:
            c = np.asarray(centre_base, dtype=np.float64)
            new = compose(pose, np.array([c[0], c[1], 0.0]))[:2]
            old = self._centre_odom
            if old is None or float(np.hypot(*(new - old))) > self.reset_distance:
                self._centre_odom = new
            else:
                self._centre_odom = (1.0 - self.alpha) * old + self.alpha * new
        if self._centre_odom is None:
            return None
        out = compose(inverse(pose), np.array([*self._centre_odom, 0.0]))[:2]
        return np.asarray(out, dtype=np.float64)
