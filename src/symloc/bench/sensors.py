"""The simulated robot of a world: its hardware, drawn once, and its sessions.

A world of the bench is mapped and then localized in by *one* robot: one lidar unit (its own
range offset and scale), one camera (its own lens distortion, which the robot knows from its
calibration) and one pair of wheels (their own calibration errors), drawn once from the sensor
regime (:mod:`symloc.sim.regimes`: ``ideal``, ``realistic``, ``heavy``) by
:func:`robot_hardware`. Each session (the mapping trip, every trial) then draws its own noise,
faults, light (exposure, white balance) and blur from that hardware:
:meth:`RobotHardware.session` gives the :class:`SensorSetup` a trial or a mapping run uses.

The localizer's filter is tuned the same way in every regime (odometry alphas
:data:`FILTER_ALPHA`, chosen on the ``ideal`` regime before the others existed); the ``ideal``
robot's own odometry noise equals them, as ``symloc experiment amcl-symmetric`` has it. The
claim gate, which carries a confirmed pose by odometry alone, is told the robot's own wheel
error as a user who measured their robot would set it (``ClaimConfig.odometry_alphas`` from
:meth:`~symloc.sim.regimes.OdometrySpec.error_alphas`, never below the gate's default; the
scenario sets it with the lidar's scale spread).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from symloc._checks import as_rng
from symloc.camera_model import CameraModel
from symloc.lidar_spec import LidarPreset
from symloc.scan import LaserScan
from symloc.sim.camera import Camera
from symloc.sim.lidar import SimulatedLidar
from symloc.sim.regimes import REGIMES, SensorRegime, get_regime
from symloc.sim.robot import OdometryNoise, RobotConfig
from symloc.sim.world import World

__all__ = [
    "FILTER_ALPHA",
    "ODOM_ALPHA",
    "REGIMES",
    "RobotHardware",
    "SensorSetup",
    "robot_hardware",
]

FloatArray = NDArray[np.float64]

FILTER_ALPHA = 0.05
"""Odometry noise alpha1..4 of the localizers' filters (symloc's and plain AMCL's alike)."""

ODOM_ALPHA = FILTER_ALPHA
"""The ``ideal`` robot's own odometry noise alpha1..4 (matched by the filters)."""

ScanFn = Callable[[World, FloatArray, tuple[float, float], float], LaserScan]
ImageFn = Callable[[World, FloatArray, tuple[float, float]], NDArray[np.uint8]]


@dataclass(frozen=True)
class SensorSetup:
    """One session's sensors of one robot.

    ``scan(world, pose, twist, stamp)`` and ``image(world, pose, twist)`` take the true pose
    (3,) at that moment (for a scan: at its first beam) and the twist ``(v [m/s], w [rad/s])``
    (motion skew, blur); ``robot_config`` is the body with its odometry error model.
    """

    regime: str
    scan: ScanFn
    image: ImageFn
    robot_config: RobotConfig


@dataclass(frozen=True)
class RobotHardware:
    """One simulated robot: its regime, lidar unit calibration, camera unit and wheels.

    ``camera.calibration`` is what the robot knows about its lens (the localizer undistorts
    with it); ``robot_config`` carries the wheels' calibration errors (the ``ideal`` robot's
    zero-mean noise is :data:`ODOM_ALPHA` in trials, the regime's own on the mapping trip).
    """

    regime: SensorRegime
    preset: LidarPreset
    camera: Camera
    robot_config: RobotConfig
    lidar_offset: float
    lidar_scale: float

    @property
    def calibration(self) -> CameraModel:
        """The camera calibration the robot is told."""
        return self.camera.calibration

    def session(self, rng: np.random.Generator | int | None, kind: str = "query") -> SensorSetup:
        """The sensors of one session (``"mapping"`` or ``"query"``), noise drawn from ``rng``."""
        gen = as_rng(rng)
        lidar = SimulatedLidar(self.preset, self.regime.lidar_faults, gen)
        # the unit's own calibration, drawn once for the robot (not per session)
        lidar.range_offset = self.lidar_offset
        lidar.range_scale = self.lidar_scale
        light = self.regime.camera_session(gen, kind)  # type: ignore[arg-type]
        camera = self.camera

        def scan(
            world: World, pose: FloatArray, twist: tuple[float, float], stamp: float
        ) -> LaserScan:
            return lidar.scan(world, pose, twist=twist, stamp=stamp)

        def image(world: World, pose: FloatArray, twist: tuple[float, float]) -> NDArray[np.uint8]:
            return camera.render(world, pose, gen, conditions=light.conditions(gen), twist=twist)

        config = self.robot_config
        if self.regime.name == "ideal" and kind == "query":
            a = ODOM_ALPHA
            config = replace(config, noise=OdometryNoise(a, a, a, a))
        return SensorSetup(self.regime.name, scan, image, config)


def robot_hardware(
    regime: str | SensorRegime,
    preset: LidarPreset,
    camera: Camera,
    rng: np.random.Generator | int | None,
) -> RobotHardware:
    """Draw one robot of ``regime``: lidar unit calibration, camera lens, wheel calibration."""
    reg = get_regime(regime)
    gen = as_rng(rng)
    unit = SimulatedLidar(preset, reg.lidar_faults, gen)
    cam = reg.camera(gen, base=camera)
    config = reg.robot_config(gen)
    return RobotHardware(reg, preset, cam, config, unit.range_offset, unit.range_scale)
