"""Simulated 2D lidar: ray casting plus the data sheet's range noise and dropouts.

The sensor figures (:class:`~symloc.lidar_spec.LidarPreset` and its presets) live in
:mod:`symloc.lidar_spec`; this module draws scans from them.

Reading semantics (REP 117, as :class:`symloc.scan.LaserScan` reads them):

- nothing hit within ``range_max`` (or the noisy range reaches it): ``+inf`` (no return);
- a hit closer than ``range_min``: ``-inf`` (too close, invalid);
- a random dropout (probability ``dropout_rate`` per beam): ``NaN`` (invalid).

Beam angles are not jittered (the data sheets give no angular noise figure).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import as_rng, check_in_range
from symloc.geometry import as_pose
from symloc.lidar_spec import LDS01, PAPER_15M, PRESETS, RPLIDAR_A2, LidarPreset
from symloc.scan import LaserScan
from symloc.sim.raycast import raycast
from symloc.sim.world import World

__all__ = [
    "LDS01",
    "LIDAR_MOUNT_HEIGHT",
    "PAPER_15M",
    "PRESETS",
    "RPLIDAR_A2",
    "LidarPreset",
    "raycast",
    "simulate_scan",
]

FloatArray = NDArray[np.float64]

LIDAR_MOUNT_HEIGHT = 0.3
"""Default height [m] of the lidar's beam plane: below the 0.4 m boards of the paper's room,
above the camera (the paper mounts the camera lower than the laser)."""


def simulate_scan(
    world: World,
    pose: ArrayLike,
    preset: LidarPreset = LDS01,
    rng: np.random.Generator | int | None = None,
    *,
    mount_height: float = LIDAR_MOUNT_HEIGHT,
    noise: bool = True,
    dropout_rate: float | None = None,
    stamp: float = 0.0,
    frame_id: str = "laser",
) -> LaserScan:
    """One lidar scan from the sensor at ``pose`` in ``world``.

    Parameters
    ----------
    world : World
    pose : array of shape (3,)
        Sensor pose x [m], y [m], theta [rad] in the world frame.
    preset : LidarPreset
        Beam layout, range limits and noise figures.
    rng : Generator, int or None
        Source of the range noise and dropouts.
    mount_height : float
        Height [m] of the beam plane; walls no taller than it are not seen.
    noise : bool
        False returns the exact ranges (no noise, no dropouts).
    dropout_rate : float, optional
        Overrides ``preset.dropout_rate``.
    stamp : float
        Time stamp [s] of the scan.

    Returns
    -------
    LaserScan
        ``n_beams`` readings; see the module docstring for +inf / -inf / NaN.
    """
    p = as_pose(pose)
    gen = as_rng(rng)
    rate = preset.dropout_rate if dropout_rate is None else dropout_rate
    rate = check_in_range(rate, "dropout_rate", 0.0, 1.0)
    true = raycast(world, p[:2], p[2] + preset.angles, min_height=mount_height)
    ranges = true.copy()
    hit = np.isfinite(true)
    if noise:
        ranges[hit] += preset.sigma(true[hit]) * gen.standard_normal(int(hit.sum()))
    ranges[ranges >= preset.range_max] = np.inf
    ranges[hit & (true < preset.range_min)] = -np.inf
    if noise and rate > 0.0:
        ranges[gen.random(ranges.size) < rate] = np.nan
    scan_time = 1.0 / preset.scan_rate
    return LaserScan(
        angle_min=preset.angle_min,
        angle_increment=preset.angle_increment,
        range_min=preset.range_min,
        range_max=preset.range_max,
        ranges=ranges,
        stamp=stamp,
        time_increment=scan_time / preset.n_beams,
        scan_time=scan_time,
        frame_id=frame_id,
    )
