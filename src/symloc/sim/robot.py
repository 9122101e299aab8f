"""A differential-drive robot with exact ground truth and noisy odometry.

The true pose follows velocity commands ``(v, w)`` exactly (arc motion, Thrun et al.,
*Probabilistic Robotics*, eq. 5.9). The wheel odometry it reports is the true motion between
two steps, decomposed into ``rot1, trans, rot2`` and corrupted by
``sample_motion_model_odometry`` (Probabilistic Robotics, Table 5.6)::

    rot1' = rot1 + N(0, alpha1 rot1^2 + alpha2 trans^2)
    trans' = trans + N(0, alpha3 trans^2 + alpha4 (rot1^2 + rot2^2))
    rot2' = rot2 + N(0, alpha1 rot2^2 + alpha2 trans^2)

(variances), then accumulated into a drifting pose in the ``odom`` frame. The alphas have the
meaning of nav2 AMCL's ``alpha1..alpha4`` (rotation from rotation, rotation from translation,
translation from translation, translation from rotation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import as_rng, check_finite_scalar, check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import as_pose, wrap_angle
from symloc.odometry import OdometryReading, rot_trans_rot, rot_trans_rot_to_pose
from symloc.sim.world import World

__all__ = [
    "DiffDriveRobot",
    "OdometryNoise",
    "RobotConfig",
    "collides",
    "integrate_velocity",
    "sample_motion_model_odometry",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class OdometryNoise:
    """The four odometry noise parameters (Probabilistic Robotics Table 5.6; nav2 AMCL names).

    Parameters
    ----------
    alpha1 : float
        Rotation noise from rotation [rad^2/rad^2].
    alpha2 : float
        Rotation noise from translation [rad^2/m^2].
    alpha3 : float
        Translation noise from translation [m^2/m^2].
    alpha4 : float
        Translation noise from rotation [m^2/rad^2].

    The defaults (0.2 each) are nav2 AMCL's defaults for a differential drive.
    """

    alpha1: float = 0.2
    alpha2: float = 0.2
    alpha3: float = 0.2
    alpha4: float = 0.2

    def __post_init__(self) -> None:
        for name in ("alpha1", "alpha2", "alpha3", "alpha4"):
            check_positive(getattr(self, name), f"OdometryNoise.{name}", allow_zero=True)

    @property
    def alphas(self) -> tuple[float, float, float, float]:
        """``(alpha1, alpha2, alpha3, alpha4)``."""
        return (self.alpha1, self.alpha2, self.alpha3, self.alpha4)


def sample_motion_model_odometry(
    rot1: ArrayLike,
    trans: ArrayLike,
    rot2: ArrayLike,
    noise: OdometryNoise,
    rng: np.random.Generator | int | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Noisy ``(rot1, trans, rot2)`` [rad, m, rad] per Probabilistic Robotics Table 5.6.

    All inputs broadcast together; returns three arrays of the broadcast shape.
    """
    gen = as_rng(rng)
    r1, tr, r2 = np.broadcast_arrays(
        np.asarray(rot1, dtype=np.float64),
        np.asarray(trans, dtype=np.float64),
        np.asarray(rot2, dtype=np.float64),
    )
    a1, a2, a3, a4 = noise.alphas
    r1_sd = np.sqrt(a1 * r1**2 + a2 * tr**2)
    tr_sd = np.sqrt(a3 * tr**2 + a4 * (r1**2 + r2**2))
    r2_sd = np.sqrt(a1 * r2**2 + a2 * tr**2)
    shape = r1.shape
    return (
        r1 + r1_sd * gen.standard_normal(shape),
        tr + tr_sd * gen.standard_normal(shape),
        r2 + r2_sd * gen.standard_normal(shape),
    )


def integrate_velocity(pose: ArrayLike, v: float, w: float, dt: float) -> FloatArray:
    """Exact pose ``(..., 3)`` after driving at ``v`` [m/s], ``w`` [rad/s] for ``dt`` [s].

    Arc motion (Probabilistic Robotics eq. 5.9); a straight line when ``|w|`` is tiny.
    """
    p = np.asarray(pose, dtype=np.float64)
    th = p[..., 2]
    if abs(w) < 1e-9:
        x = p[..., 0] + v * dt * np.cos(th)
        y = p[..., 1] + v * dt * np.sin(th)
        return np.stack([x, y, wrap_angle(th)], axis=-1)
    r = v / w
    th2 = th + w * dt
    x = p[..., 0] - r * np.sin(th) + r * np.sin(th2)
    y = p[..., 1] + r * np.cos(th) - r * np.cos(th2)
    return np.stack([x, y, wrap_angle(th2)], axis=-1)


def collides(
    world: World, positions: ArrayLike, radius: float, *, min_height: float = 0.05
) -> NDArray[np.bool_]:
    """``(N,)`` True where a round robot of ``radius`` [m] at ``positions (N, 2)`` touches an
    obstacle taller than ``min_height`` [m]."""
    r = check_positive(radius, "radius")
    return world.distance(positions, min_height=min_height) < r


@dataclass(frozen=True)
class RobotConfig:
    """Settings of the simulated differential-drive robot.

    Parameters
    ----------
    radius : float
        Footprint radius [m] for collision checks (TurtleBot3 burger: 0.105 m; Kobuki 0.177 m).
    max_v : float
        Speed limit [m/s]; commands beyond it raise.
    max_w : float
        Turn-rate limit [rad/s]; commands beyond it raise.
    noise : OdometryNoise
        Odometry noise alphas.
    """

    radius: float = 0.177
    max_v: float = 0.7
    max_w: float = 3.0
    noise: OdometryNoise = OdometryNoise()

    def __post_init__(self) -> None:
        check_positive(self.radius, "RobotConfig.radius")
        check_positive(self.max_v, "RobotConfig.max_v")
        check_positive(self.max_w, "RobotConfig.max_w")
        if not isinstance(self.noise, OdometryNoise):
            raise ConfigurationError("RobotConfig.noise: expected an OdometryNoise")


class DiffDriveRobot:
    """A differential-drive robot in a world: exact true pose, noisy odometry.

    Parameters
    ----------
    pose : array of shape (3,)
        Initial true pose x [m], y [m], theta [rad] in the world (map) frame.
    config : RobotConfig
    rng : Generator, int or None
        Source of the odometry noise.
    world : World, optional
        If given, :meth:`step` refuses motions that would collide with its obstacles.
    odom_origin : array of shape (3,), optional
        Initial odometry pose (default zero: odometry starts at its own origin).
    """

    def __init__(
        self,
        pose: ArrayLike,
        config: RobotConfig | None = None,
        rng: np.random.Generator | int | None = None,
        *,
        world: World | None = None,
        odom_origin: ArrayLike = (0.0, 0.0, 0.0),
    ) -> None:
        self.config = RobotConfig() if config is None else config
        self._rng = as_rng(rng)
        self._pose = as_pose(pose).copy()
        self._odom = as_pose(odom_origin, "odom_origin").copy()
        self._time = 0.0
        self.world = world

    @property
    def pose(self) -> FloatArray:
        """The exact (ground-truth) pose ``(3,)`` in the world frame (a copy)."""
        return self._pose.copy()

    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return self._time

    def odometry(self) -> OdometryReading:
        """The current noisy odometry reading (pose in the ``odom`` frame, stamp)."""
        return OdometryReading(self._odom.copy(), self._time)

    def teleport(self, pose: ArrayLike) -> None:
        """Move the true pose without any odometry (a kidnapping)."""
        self._pose = as_pose(pose).copy()

    def collides_at(self, pose: ArrayLike) -> bool:
        """True if the robot's footprint at ``pose`` would touch an obstacle of the world."""
        if self.world is None:
            return False
        p = as_pose(pose)
        return bool(collides(self.world, p[None, :2], self.config.radius)[0])

    def step(self, v: float, w: float, dt: float) -> bool:
        """Drive at ``v`` [m/s] and ``w`` [rad/s] for ``dt`` [s].

        Returns False (and does not move, but time passes) if the motion would end in a
        collision; else updates the true pose and the noisy odometry and returns True.
        """
        v = check_finite_scalar(v, "v")
        w = check_finite_scalar(w, "w")
        dt = check_positive(dt, "dt")
        if abs(v) > self.config.max_v:
            raise ConfigurationError(f"v: |v| must be <= max_v = {self.config.max_v} m/s, got {v}")
        if abs(w) > self.config.max_w:
            raise ConfigurationError(
                f"w: |w| must be <= max_w = {self.config.max_w} rad/s, got {w}"
            )
        new = integrate_velocity(self._pose, v, w, dt)
        self._time += dt
        if self.collides_at(new):
            return False
        r1, tr, r2 = rot_trans_rot(self._pose, new, min_trans=1e-9)
        if v < 0 and float(tr) > 0:  # driving backwards: heading of travel is behind us
            r1 = wrap_angle(r1 + math.pi)
            r2 = wrap_angle(r2 - math.pi)
            tr = -tr
        n1, nt, n2 = sample_motion_model_odometry(r1, tr, r2, self.config.noise, self._rng)
        self._odom = rot_trans_rot_to_pose(self._odom, n1, nt, n2)
        self._pose = new
        return True

    def drive(self, v: float, w: float, duration: float, dt: float = 0.1) -> bool:
        """Repeat :meth:`step` for ``duration`` [s]; stops early (returns False) on collision."""
        duration = check_positive(duration, "duration")
        n = max(1, round(duration / dt))
        return all(self.step(v, w, duration / n) for _ in range(n))
