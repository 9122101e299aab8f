"""A differential-drive robot with exact ground truth and noisy odometry.

Each step of :meth:`DiffDriveRobot.step` goes through four stages; with the default
:class:`RobotConfig` only the last is active, and the robot is the one symloc always had (the
true pose follows the command exactly):

1. **Actuation.** The wheel speed controllers do not track the command exactly: each wheel's
   speed is ``(1 + e)`` times its commanded speed, ``e ~ N(0, actuation_noise)`` per wheel and
   step, so the executed ``(v, w)`` differs from the commanded one (a turn appears while driving
   straight). The wheels turn by the executed motion (arc motion, Thrun et al., *Probabilistic
   Robotics*, eq. 5.9).
2. **Wheel slip.** While turning on the spot or accelerating hard, an episode of slip may start
   (:class:`WheelSlip`): for its duration the robot moves only ``(1 - s)`` of what its wheels
   turn. The true pose follows the slipped motion; the wheels report the full one.
3. **Systematic calibration error** (UMBmark's error sources, Borenstein and Feng 1996): the
   odometry converts wheel turns with slightly wrong wheel diameters and wheel base, so it
   reports travelled distance x ``(1 + odom_scale_error)``, rotation x
   ``(1 + odom_rotation_error)``, and a heading drift of ``odom_heading_drift`` [rad] per metre
   (unequal wheel diameters).
4. **Zero-mean noise** on the reported increment, decomposed into ``rot1, trans, rot2`` and
   corrupted by ``sample_motion_model_odometry`` (Probabilistic Robotics, Table 5.6)::

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
    "WheelSlip",
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
class WheelSlip:
    """Episodes of wheel slip: the robot moves less than its wheels turn.

    An episode can start in a step where the robot turns on the spot (``|v| < spot_speed`` and
    ``|w| > spot_turn``) or its commanded speed changes faster than ``accel_threshold``; it
    starts with probability ``1 - exp(-rate dt)``, lasts an exponentially distributed time of
    mean ``duration``, and during it the robot moves ``(1 - s)`` of the wheels' motion, ``s``
    uniform in ``[fraction_min, fraction_max]`` (drawn per episode).

    Parameters
    ----------
    rate : float
        Episodes per second [1/s] while a trigger holds (0: never slips).
    duration : float
        Mean episode length [s], > 0.
    fraction_min, fraction_max : float
        Range of the lost fraction of motion, 0 <= min <= max < 1.
    spot_speed : float
        Largest |v| [m/s] that counts as turning on the spot.
    spot_turn : float
        Smallest |w| [rad/s] that counts as turning on the spot.
    accel_threshold : float
        Smallest change of the commanded speed [m/s^2] that counts as hard acceleration.
    """

    rate: float = 0.0
    duration: float = 0.3
    fraction_min: float = 0.05
    fraction_max: float = 0.2
    spot_speed: float = 0.05
    spot_turn: float = 0.3
    accel_threshold: float = 0.5

    def __post_init__(self) -> None:
        check_positive(self.rate, "WheelSlip.rate", allow_zero=True)
        check_positive(self.duration, "WheelSlip.duration")
        for name in ("spot_speed", "spot_turn", "accel_threshold"):
            check_positive(getattr(self, name), f"WheelSlip.{name}", allow_zero=True)
        lo = check_finite_scalar(self.fraction_min, "WheelSlip.fraction_min")
        hi = check_finite_scalar(self.fraction_max, "WheelSlip.fraction_max")
        if not 0.0 <= lo <= hi < 1.0:
            raise ConfigurationError(
                "WheelSlip.fraction_min, fraction_max: expected 0 <= min <= max < 1, got"
                f" {lo}, {hi}"
            )


@dataclass(frozen=True)
class RobotConfig:
    """Settings of the simulated differential-drive robot (see the module docstring).

    The defaults are the robot symloc always simulated: exact actuation, no slip, no
    calibration error, nav2 AMCL's default odometry noise. A regime of
    :mod:`symloc.sim.regimes` draws realistic per-robot values.

    Parameters
    ----------
    radius : float
        Footprint radius [m] for collision checks (TurtleBot3 burger: 0.105 m; Kobuki 0.177 m).
    max_v : float
        Speed limit [m/s]; commands beyond it raise.
    max_w : float
        Turn-rate limit [rad/s]; commands beyond it raise.
    noise : OdometryNoise
        Zero-mean odometry noise alphas.
    wheel_base : float
        Distance [m] between the wheels (Kobuki 0.230 m), for the per-wheel actuation error.
    odom_scale_error : float
        Reported distance / true wheel distance - 1 (e.g. 0.015: odometry says 1.015 m per
        metre), in (-0.5, 0.5).
    odom_rotation_error : float
        Reported rotation / true rotation - 1 (wheel-base error), in (-0.5, 0.5).
    odom_heading_drift : float
        Heading error [rad] the odometry adds per metre travelled (unequal wheel diameters).
    actuation_noise : float
        Standard deviation of each wheel's speed error, a fraction of its commanded speed
        (>= 0, < 0.5).
    slip : WheelSlip
        Wheel slip episodes (default: none).
    """

    radius: float = 0.177
    max_v: float = 0.7
    max_w: float = 3.0
    noise: OdometryNoise = OdometryNoise()
    wheel_base: float = 0.23
    odom_scale_error: float = 0.0
    odom_rotation_error: float = 0.0
    odom_heading_drift: float = 0.0
    actuation_noise: float = 0.0
    slip: WheelSlip = WheelSlip()

    def __post_init__(self) -> None:
        check_positive(self.radius, "RobotConfig.radius")
        check_positive(self.max_v, "RobotConfig.max_v")
        check_positive(self.max_w, "RobotConfig.max_w")
        check_positive(self.wheel_base, "RobotConfig.wheel_base")
        if not isinstance(self.noise, OdometryNoise):
            raise ConfigurationError("RobotConfig.noise: expected an OdometryNoise")
        if not isinstance(self.slip, WheelSlip):
            raise ConfigurationError("RobotConfig.slip: expected a WheelSlip")
        for name in ("odom_scale_error", "odom_rotation_error"):
            v = check_finite_scalar(getattr(self, name), f"RobotConfig.{name}")
            if not -0.5 < v < 0.5:
                raise ConfigurationError(
                    f"RobotConfig.{name}: expected a fraction in (-0.5, 0.5), got {v}"
                )
        check_finite_scalar(self.odom_heading_drift, "RobotConfig.odom_heading_drift")
        a = check_positive(self.actuation_noise, "RobotConfig.actuation_noise", allow_zero=True)
        if a >= 0.5:
            raise ConfigurationError(
                f"RobotConfig.actuation_noise: expected a fraction in [0, 0.5), got {a}"
            )

    @property
    def has_systematic_error(self) -> bool:
        """True if the odometry has a calibration error (scale, rotation or drift)."""
        return bool(self.odom_scale_error or self.odom_rotation_error or self.odom_heading_drift)


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
        self._last_v = 0.0
        self._slip_left = 0.0
        self._slip_frac = 0.0
        self.world = world
        #: True while the last step slipped (the robot moved less than its wheels).
        self.slipping = False

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

    def _slip_fraction(self, v: float, w: float, dt: float) -> float:
        """Fraction of the wheels' motion lost to slip in this step (0 outside episodes)."""
        sl = self.config.slip
        if sl.rate <= 0.0:
            return 0.0
        if self._slip_left > 0.0:
            self._slip_left -= dt
            return self._slip_frac
        spot = abs(v) < sl.spot_speed and abs(w) > sl.spot_turn
        accel = abs(v - self._last_v) / dt > sl.accel_threshold
        if (spot or accel) and self._rng.random() < -math.expm1(-sl.rate * dt):
            self._slip_left = float(self._rng.exponential(sl.duration)) - dt
            self._slip_frac = float(self._rng.uniform(sl.fraction_min, sl.fraction_max))
            return self._slip_frac
        return 0.0

    def step(self, v: float, w: float, dt: float) -> bool:
        """Drive with the command ``v`` [m/s], ``w`` [rad/s] for ``dt`` [s].

        Returns False (and does not move, but time passes) if the motion would end in a
        collision; else updates the true pose and the odometry and returns True. The true
        motion differs from the command by the actuation error and slip; the odometry reports
        the wheels' motion through the calibration error and noise (module docstring).
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
        cfg = self.config
        ve, we = v, w
        if cfg.actuation_noise > 0.0:
            half = 0.5 * cfg.wheel_base
            e = self._rng.normal(0.0, cfg.actuation_noise, 2)
            vl = (v - w * half) * (1.0 + float(e[0]))
            vr = (v + w * half) * (1.0 + float(e[1]))
            ve, we = 0.5 * (vl + vr), (vr - vl) / cfg.wheel_base
        s = self._slip_fraction(v, w, dt)
        self._last_v = v
        self.slipping = s > 0.0
        wheels = integrate_velocity(self._pose, ve, we, dt)
        new = wheels if s == 0.0 else integrate_velocity(self._pose, ve * (1 - s), we * (1 - s), dt)
        self._time += dt
        if self.collides_at(new):
            return False
        r1, tr, r2 = rot_trans_rot(self._pose, wheels, min_trans=1e-9)
        if ve < 0 and float(tr) > 0:  # driving backwards: heading of travel is behind us
            r1 = wrap_angle(r1 + math.pi)
            r2 = wrap_angle(r2 - math.pi)
            tr = -tr
        if cfg.has_systematic_error:
            tr = tr * (1.0 + cfg.odom_scale_error)
            drift = 0.5 * cfg.odom_heading_drift * tr
            r1 = r1 * (1.0 + cfg.odom_rotation_error) + drift
            r2 = r2 * (1.0 + cfg.odom_rotation_error) + drift
        n1, nt, n2 = sample_motion_model_odometry(r1, tr, r2, cfg.noise, self._rng)
        self._odom = rot_trans_rot_to_pose(self._odom, n1, nt, n2)
        self._pose = new
        return True

    def drive(self, v: float, w: float, duration: float, dt: float = 0.1) -> bool:
        """Repeat :meth:`step` for ``duration`` [s]; stops early (returns False) on collision."""
        duration = check_positive(duration, "duration")
        n = max(1, round(duration / dt))
        return all(self.step(v, w, duration / n) for _ in range(n))
