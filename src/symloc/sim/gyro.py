"""A simulated single-axis yaw-rate gyro and gyro-odometry for the mapping trip.

The paper's robot base (Kobuki) carries a factory-calibrated gyro; its driver reads the
ST L3G4200D 3-axis MEMS gyro at 100 Hz (``kobuki_driver``/``kobuki_node``:
``digit_to_dps = 0.00875``, "comes from datasheet of 3d gyro [L3G4200D]") and the base uses
the gyro's heading, not the wheels', for its odometry heading. :data:`L3G4200D` takes the noise
figures from ST's data sheet (L3G4200D, Doc ID 17116, Table 4, FS = 250 dps):

- rate noise density ``Rn`` = 0.03 dps/sqrt(Hz) (white rate noise: an angle random walk);
- zero-rate level change with temperature ``OffDr`` = +-0.03 dps/degC; the factory/start-up
  calibration removes the static zero-rate level (+-10 dps raw), so the residual bias is the
  drift of a 2 degC temperature change during the trip (0.06 dps, drawn once per trip);
- sensitivity change with temperature ``SoDr`` = +-2 % over -40..85 degC; over a 2 degC change
  that is negligible, and the residual scale error of the calibration is taken as 0.2 % (the
  data sheet's non-linearity, 0.2 % FS).

:class:`GyroOdometryBody` wraps a simulated body for the mapping trip only: the odometry it
reports integrates the wheels' travelled distance along the gyro's heading, as the Kobuki does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import relative, wrap_angle
from symloc.odometry import OdometryReading

__all__ = ["L3G4200D", "GyroOdometryBody", "GyroSpec", "SimulatedGyro"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class GyroSpec:
    """Noise of a single-axis yaw-rate gyro after its start-up calibration.

    noise_density [deg/s/sqrt(Hz)] white rate noise; bias_std [deg/s] residual bias (drawn once
    per trip); scale_std [fraction] residual scale-factor error (drawn once per trip);
    source: where the figures come from.
    """

    noise_density: float
    bias_std: float
    scale_std: float
    source: str = ""

    def __post_init__(self) -> None:
        check_positive(self.noise_density, "GyroSpec.noise_density")
        for name in ("bias_std", "scale_std"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0.0):
                raise ConfigurationError(
                    f"GyroSpec.{name}: expected a finite value >= 0, got {v!r}"
                )


#: The Kobuki's gyro (ST L3G4200D), figures from its data sheet (see the module docstring).
L3G4200D = GyroSpec(
    noise_density=0.03,
    bias_std=0.06,
    scale_std=0.002,
    source="ST L3G4200D data sheet (Doc ID 17116), Table 4: Rn 0.03 dps/sqrt(Hz), OffDr "
    "0.03 dps/degC (x 2 degC), NL 0.2 % FS; Kobuki reads it at 100 Hz (kobuki_driver)",
)


class SimulatedGyro:
    """Integrated yaw-rate measurements: ``measure(dtheta, dt)`` -> measured heading change.

    The measured change over ``dt`` [s] is ``(1 + s) dtheta + b dt + n`` with ``n`` ~
    N(0, (Rn^2) dt) (angle random walk of the white rate noise), ``s`` and ``b`` drawn once.
    """

    def __init__(self, spec: GyroSpec, rng: np.random.Generator) -> None:
        self.spec = spec
        self.rng = rng
        self.scale = float(rng.normal(0.0, spec.scale_std))
        self.bias = math.radians(float(rng.normal(0.0, spec.bias_std)))  # rad/s
        self._nd = math.radians(spec.noise_density)  # rad/s/sqrt(Hz)

    def measure(self, dtheta: float, dt: float) -> float:
        """Measured heading change [rad] for a true change ``dtheta`` [rad] over ``dt`` [s]."""
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ConfigurationError(f"dt: expected a finite value > 0 s, got {dt!r}")
        noise = float(self.rng.normal(0.0, self._nd * math.sqrt(dt)))
        return (1.0 + self.scale) * float(dtheta) + self.bias * dt + noise


class GyroOdometryBody:
    """A body whose odometry takes its heading from a gyro (for the mapping trip).

    Wraps anything with ``pose``, ``odom`` and ``drive(v, w, dt)`` (e.g.
    :class:`~symloc.bench.episode.RobotBody`). Each drive step takes the wheel odometry's
    travelled distance (in the wheels' own increment) and turns the pose by the gyro's measured
    heading change of the true motion; the position integrates along the gyro heading (midpoint).
    The fused odometry starts equal to the wrapped body's odometry.
    """

    def __init__(self, body: Any, gyro: SimulatedGyro) -> None:
        self.body = body
        self.gyro = gyro
        self._pose = np.asarray(body.odom.pose, dtype=np.float64).copy()
        self._stamp = float(body.odom.stamp)

    @property
    def pose(self) -> FloatArray:
        return np.asarray(self.body.pose, dtype=np.float64)

    @property
    def odom(self) -> OdometryReading:
        return OdometryReading(self._pose.copy(), self._stamp)

    @property
    def collisions(self) -> int:
        return int(getattr(self.body, "collisions", 0))

    @property
    def twist(self) -> tuple[float, float]:
        """The wrapped body's last commanded (v [m/s], w [rad/s])."""
        twist: tuple[float, float] = getattr(self.body, "twist", (0.0, 0.0))
        return twist

    def drive(self, v: float, w: float, dt: float) -> OdometryReading:
        true0 = self.body.pose
        wheel0 = np.asarray(self.body.odom.pose, dtype=np.float64)
        reading = self.body.drive(v, w, dt)
        true1 = self.body.pose
        step = relative(wheel0, np.asarray(reading.pose, dtype=np.float64))
        dist = float(math.hypot(step[0], step[1])) * (1.0 if step[0] >= 0.0 else -1.0)
        dth = self.gyro.measure(float(wrap_angle(true1[2] - true0[2])), dt)
        mid = self._pose[2] + 0.5 * dth
        self._pose = np.array(
            [
                self._pose[0] + dist * math.cos(mid),
                self._pose[1] + dist * math.sin(mid),
                float(wrap_angle(self._pose[2] + dth)),
            ]
        )
        self._stamp = float(reading.stamp)
        return self.odom
