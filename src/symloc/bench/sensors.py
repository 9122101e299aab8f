"""The simulated sensors and body of one robot, as a trial or a mapping run uses them.

A :class:`SensorSetup` bundles, for one robot in one session (mapping or query), the lidar it
scans with, the camera it photographs with and the configuration of its wheels. The regime
(``ideal`` today: the data-sheet range noise, exact actuation, Thrun odometry noise) decides
what each of them gets wrong; :func:`sensor_setup` draws one robot's sensors from it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import as_rng
from symloc.errors import ConfigurationError
from symloc.lidar_spec import LidarPreset
from symloc.scan import LaserScan
from symloc.sim.camera import Camera
from symloc.sim.lidar import simulate_scan
from symloc.sim.robot import OdometryNoise, RobotConfig
from symloc.sim.world import World

__all__ = ["ODOM_ALPHA", "REGIMES", "SensorSetup", "sensor_setup"]

FloatArray = NDArray[np.float64]

#: Odometry noise alpha1..4 of the ``ideal`` regime (as ``symloc experiment amcl-symmetric``).
ODOM_ALPHA = 0.05

REGIMES = ("ideal",)
"""Sensor regimes :func:`sensor_setup` knows."""

ScanFn = Callable[[World, FloatArray, tuple[float, float], float], LaserScan]
ImageFn = Callable[[World, FloatArray, tuple[float, float]], NDArray[np.uint8]]


@dataclass(frozen=True)
class SensorSetup:
    """One robot's sensors in one session.

    ``scan(world, pose, twist, stamp)`` and ``image(world, pose, twist)`` take the true pose
    (3,) and the twist ``(v [m/s], w [rad/s])`` at that moment (for motion skew and blur);
    ``robot_config`` is the body with its odometry error model; ``odom_alphas`` are the
    alpha1..4 an AMCL tuned for this robot would use (nav2's tuning guide: match the robot).
    """

    regime: str
    scan: ScanFn
    image: ImageFn
    robot_config: RobotConfig
    odom_alphas: tuple[float, float, float, float]
    camera: Camera


def sensor_setup(
    regime: str,
    preset: LidarPreset,
    camera: Camera,
    rng: np.random.Generator | int | None,
    *,
    session: str = "query",
) -> SensorSetup:
    """Draw one robot's sensors for ``session`` (``"mapping"`` or ``"query"``) of ``regime``."""
    if regime not in REGIMES:
        raise ConfigurationError(f"regime: expected one of {', '.join(REGIMES)}, got {regime!r}")
    if session not in ("mapping", "query"):
        raise ConfigurationError(f"session: expected 'mapping' or 'query', got {session!r}")
    gen = as_rng(rng)

    def scan(world: World, pose: FloatArray, twist: tuple[float, float], stamp: float) -> Any:
        return simulate_scan(world, pose, preset, gen, stamp=stamp)

    def image(world: World, pose: FloatArray, twist: tuple[float, float]) -> Any:
        return camera.render(world, pose, gen)

    a = ODOM_ALPHA
    return SensorSetup(
        regime=regime,
        scan=scan,
        image=image,
        robot_config=RobotConfig(noise=OdometryNoise(a, a, a, a)),
        odom_alphas=(a, a, a, a),
        camera=camera,
    )
