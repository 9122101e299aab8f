"""The embedded simulated world: rooms, lidar, odometry, camera.

Submodules: :mod:`~symloc.sim.world` (``World``), :mod:`~symloc.sim.rooms` (builders, ``Room``,
``build_room``), :mod:`~symloc.sim.world_file` (YAML world files: ``WorldSpec``,
``load_world_file``; the geometry in :mod:`~symloc.sim.world_build`),
:mod:`~symloc.sim.generator` (``FAMILIES``, ``generate_world``),
:mod:`~symloc.sim.symmetry_truth` (the true symmetry order, computed from the geometry),
:mod:`~symloc.sim.people` (people walking), :mod:`~symloc.sim.free_space` (where a robot fits),
:mod:`~symloc.sim.raycast`, :mod:`~symloc.sim.lidar` (presets, ``simulate_scan``,
``LidarFaults``, ``SimulatedLidar``), :mod:`~symloc.sim.rasterize` (``world_to_grid``),
:mod:`~symloc.sim.robot` (differential drive, odometry noise, calibration error, actuation error,
wheel slip), :mod:`~symloc.sim.camera` (``Camera``, ``CameraConditions``),
:mod:`~symloc.sim.textures` and :mod:`~symloc.sim.poster` (the pool of wall textures),
:mod:`~symloc.sim.regimes` (the named sensor regimes ``ideal``, ``realistic``, ``heavy`` with
their sources).

The names below are imported from their modules on first use, so that importing one light module
of the package (:mod:`~symloc.sim.odometry_noise` for SLAM on a log) does not load the lidar,
the rooms, the world files and the textures (OpenCV, numba through the symmetry features).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import lazy_loader

if TYPE_CHECKING:
    from symloc.sim.lidar import (
        LDS01,
        PAPER_15M,
        PRESETS,
        RPLIDAR_A2,
        LidarFaults,
        LidarPreset,
        SimulatedLidar,
        simulate_scan,
    )
    from symloc.sim.raycast import raycast
    from symloc.sim.robot import DiffDriveRobot, OdometryNoise, RobotConfig, WheelSlip
    from symloc.sim.rooms import ROOM_NAMES, Room, build_room
    from symloc.sim.world import World
    from symloc.sim.world_file import WorldSpec, load_world_file, save_world_file

#: Submodule -> the public names it defines (imported on first use).
_SUBMODULE_ATTRS = {
    "lidar": [
        "LDS01",
        "PAPER_15M",
        "PRESETS",
        "RPLIDAR_A2",
        "LidarFaults",
        "LidarPreset",
        "SimulatedLidar",
        "simulate_scan",
    ],
    "raycast": ["raycast"],
    "robot": ["DiffDriveRobot", "OdometryNoise", "RobotConfig", "WheelSlip"],
    "rooms": ["ROOM_NAMES", "Room", "build_room"],
    "world": ["World"],
    "world_file": ["WorldSpec", "load_world_file", "save_world_file"],
}

__all__ = [
    "LDS01",
    "PAPER_15M",
    "PRESETS",
    "ROOM_NAMES",
    "RPLIDAR_A2",
    "DiffDriveRobot",
    "LidarFaults",
    "LidarPreset",
    "OdometryNoise",
    "RobotConfig",
    "Room",
    "SimulatedLidar",
    "WheelSlip",
    "World",
    "WorldSpec",
    "build_room",
    "load_world_file",
    "raycast",
    "save_world_file",
    "simulate_scan",
]


# PEP 562 through scientific-python's lazy_loader (as scikit-image does)
__getattr__, __dir__, _ = lazy_loader.attach(__name__, submod_attrs=_SUBMODULE_ATTRS)
