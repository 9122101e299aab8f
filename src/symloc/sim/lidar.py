"""Simulated 2D lidar: ray casting plus the data sheet's range noise, and a real unit's faults.

The sensor figures (:class:`~symloc.lidar_spec.LidarPreset` and its presets) live in
:mod:`symloc.lidar_spec`; this module draws scans from them.

Two ways to scan:

- :func:`simulate_scan`: the data sheet's range noise and the preset's random dropouts only,
  every beam cast from one pose (an ideal sensor; unchanged for existing callers).
- :class:`SimulatedLidar`: one physical unit of a preset with a :class:`LidarFaults` model: a
  range bias and scale error drawn once per unit, random dropouts, angular jitter, glass that
  the beam mostly passes through, dark surfaces that return nothing at long range or oblique
  incidence, mixed pixels at depth edges, and motion skew (each beam cast from the pose at its
  own time within the revolution). The figures that a regime uses, with their sources, are in
  :mod:`symloc.sim.regimes`.

Reading semantics (REP 117, as :class:`symloc.scan.LaserScan` reads them):

- nothing hit within ``range_max`` (or the noisy range reaches it), and a physical no-return
  (glass passed out of the cone of reflection and lost, a dark surface too far): ``+inf``,
  as drivers such as ``rplidar_ros`` publish a sample without a valid echo;
- a hit closer than ``range_min``: ``-inf`` (too close, invalid);
- a random dropout (probability ``dropout_rate`` per beam): ``NaN`` (invalid).

Time stamps follow sensor_msgs/LaserScan: the scan's ``stamp`` is the acquisition time of the
first beam (index 0), beam ``i`` is taken at ``stamp + i * time_increment``, beams in index
order (counter-clockwise), one revolution per ``1 / scan_rate`` seconds. With motion skew the
ranges are those a sensor moving with the robot's twist measures; the beam angles stay the
nominal ones in the sensor frame, as a driver reports them. Without it every beam is cast from
the pose at the stamp, and ``time_increment`` is 0 to say so (an instantaneous scan).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ndtr

from symloc._checks import as_rng, check_finite_scalar, check_in_range
from symloc.errors import ConfigurationError
from symloc.geometry import as_pose
from symloc.lidar_spec import LDS01, PAPER_15M, PRESETS, RPLIDAR_A2, LidarPreset
from symloc.scan import LaserScan
from symloc.sim.raycast import raycast, raycast_nearest
from symloc.sim.world import MATERIAL_DARK, MATERIAL_GLASS, World

__all__ = [
    "LDS01",
    "LIDAR_MOUNT_HEIGHT",
    "PAPER_15M",
    "PRESETS",
    "RPLIDAR_A2",
    "LidarFaults",
    "LidarPreset",
    "SimulatedLidar",
    "beam_poses",
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
        time_increment=0.0,  # every beam from ``pose``: an instantaneous (unskewed) scan
        scan_time=scan_time,
        frame_id=frame_id,
    )


@dataclass(frozen=True)
class LidarFaults:
    """What a real 2D lidar does beyond the data sheet's zero-mean range noise.

    The defaults are no fault at all (a :class:`SimulatedLidar` with ``LidarFaults()`` draws the
    same scans as :func:`simulate_scan` from the same seed). Figures for real units, with their
    sources, are in :mod:`symloc.sim.regimes`.

    Parameters
    ----------
    dropout_rate : float
        Probability in [0, 1) that a beam returns NaN (an invalid sample), independently per
        beam, on top of the preset's own ``dropout_rate``.
    angle_jitter_bins : float
        Standard deviation of the difference between a beam's true and reported direction, in
        units of the beam spacing (>= 0). A driver that bins samples onto a fixed angular grid
        (``rplidar_ros`` with ``angle_compensate``) has a uniform error of +-half a bin:
        ``1 / sqrt(12) = 0.29`` bins.
    range_bias_std : float
        Standard deviation [m] of the unit's constant range offset (drawn once per unit).
    range_scale_std : float
        Standard deviation of the unit's range scale error, a fraction of the range (drawn
        once per unit): a reading is ``(1 + scale) r + offset`` plus noise.
    glass_reflect_angle : float
        Half-angle [rad] of the cone around the glass's normal inside which the beam can be
        reflected back to the sensor, in [0, pi/2]. pi/2 with ``glass_reflect_prob = 1`` makes
        glass opaque (the default: a glass panel is seen like a wall).
    glass_reflect_prob : float
        Probability in [0, 1] that a beam inside that cone returns the glass's range.
    glass_no_return_prob : float
        Probability in [0, 1] that a beam that is not reflected returns nothing (``+inf``);
        otherwise it passes through and returns whatever lies behind the glass.
    dark_range_fraction : float
        Range at which a dark (``MATERIAL_DARK``) surface met head-on returns nothing half the
        time, as a fraction of the preset's ``range_max`` (> 0; ``inf``: dark surfaces are seen
        like any other). The returned power falls as ``cos(incidence) / r^2``, so the
        probability of no return grows with range and with the angle of incidence.
    dark_spread : float
        Standard deviation (> 0) of the log of the returned power from beam to beam (speckle,
        surface texture): how gradual the change from seen to unseen is.
    mixed_pixel_prob : float
        Probability in [0, 1] that a depth edge between two adjacent beams (different surfaces,
        ranges differing by more than ``mixed_min_jump``) falls inside one of the two beams'
        footprints; that beam then reads a range between the foreground and the background.
    mixed_min_jump : float
        Smallest range difference [m] (> 0) that counts as a depth edge.
    motion_skew : bool
        Cast each beam from the robot's pose at that beam's time within the revolution (the
        scan is not instantaneous); False casts every beam from the scan's pose.
    """

    dropout_rate: float = 0.0
    angle_jitter_bins: float = 0.0
    range_bias_std: float = 0.0
    range_scale_std: float = 0.0
    glass_reflect_angle: float = math.pi / 2
    glass_reflect_prob: float = 1.0
    glass_no_return_prob: float = 0.0
    dark_range_fraction: float = math.inf
    dark_spread: float = 0.5
    mixed_pixel_prob: float = 0.0
    mixed_min_jump: float = 0.1
    motion_skew: bool = False

    def __post_init__(self) -> None:
        if not 0.0 <= self.dropout_rate < 1.0:
            raise ConfigurationError(
                f"LidarFaults.dropout_rate: expected a value in [0, 1), got {self.dropout_rate}"
            )
        for name in ("angle_jitter_bins", "range_bias_std", "range_scale_std"):
            v = check_finite_scalar(getattr(self, name), f"LidarFaults.{name}")
            if v < 0:
                raise ConfigurationError(f"LidarFaults.{name}: expected a value >= 0, got {v}")
        check_in_range(
            self.glass_reflect_angle, "LidarFaults.glass_reflect_angle", 0.0, math.pi / 2
        )
        for name in ("glass_reflect_prob", "glass_no_return_prob", "mixed_pixel_prob"):
            check_in_range(getattr(self, name), f"LidarFaults.{name}", 0.0, 1.0)
        if not self.dark_range_fraction > 0:
            raise ConfigurationError(
                "LidarFaults.dark_range_fraction: expected a value > 0 (inf: off), got"
                f" {self.dark_range_fraction}"
            )
        for name in ("dark_spread", "mixed_min_jump"):
            v = check_finite_scalar(getattr(self, name), f"LidarFaults.{name}")
            if v <= 0:
                raise ConfigurationError(f"LidarFaults.{name}: expected a value > 0, got {v}")
        if not isinstance(self.motion_skew, bool):
            raise ConfigurationError(
                f"LidarFaults.motion_skew: expected True or False, got {self.motion_skew!r}"
            )

    @property
    def glass_opaque(self) -> bool:
        """True when glass always returns its own range (reflected at every incidence)."""
        return self.glass_reflect_prob >= 1.0 and self.glass_reflect_angle >= math.pi / 2

    def as_dict(self) -> dict[str, float | bool]:
        """The fields by name (for printing a configuration)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


def beam_poses(pose: ArrayLike, twist: tuple[float, float], times: ArrayLike) -> FloatArray:
    """Poses ``(N, 3)`` of a robot that is at ``pose`` at time 0 and keeps ``twist`` constant.

    ``twist`` is ``(v [m/s], w [rad/s])``; ``times (N,)`` [s]. Arc motion (Probabilistic
    Robotics eq. 5.9); headings are not wrapped.
    """
    p = as_pose(pose)
    t = np.asarray(times, dtype=np.float64)
    v, w = float(twist[0]), float(twist[1])
    th = p[2] + w * t
    if abs(w) < 1e-9:
        x = p[0] + v * t * math.cos(p[2])
        y = p[1] + v * t * math.sin(p[2])
    else:
        r = v / w
        x = p[0] + r * (np.sin(th) - math.sin(p[2]))
        y = p[1] - r * (np.cos(th) - math.cos(p[2]))
    return np.column_stack([np.broadcast_to(x, t.shape), np.broadcast_to(y, t.shape), th])


class SimulatedLidar:
    """One physical lidar: a preset, a fault model, and this unit's own calibration errors.

    Parameters
    ----------
    preset : LidarPreset
        Beam layout, range limits and data-sheet noise.
    faults : LidarFaults, optional
        Fault model (default: none).
    rng : Generator, int or None
        Draws the unit's range offset and scale once, here, then every scan's noise and faults.

    Attributes
    ----------
    range_offset : float
        This unit's constant range error [m].
    range_scale : float
        This unit's range scale error (fraction of the range).
    """

    def __init__(
        self,
        preset: LidarPreset,
        faults: LidarFaults | None = None,
        rng: np.random.Generator | int | None = None,
    ) -> None:
        if not isinstance(preset, LidarPreset):
            raise ConfigurationError(f"preset: expected a LidarPreset, got {preset!r}")
        self.preset = preset
        self.faults = LidarFaults() if faults is None else faults
        if not isinstance(self.faults, LidarFaults):
            raise ConfigurationError(f"faults: expected LidarFaults, got {self.faults!r}")
        self.rng = as_rng(rng)
        f = self.faults
        self.range_offset = (
            float(self.rng.normal(0.0, f.range_bias_std)) if f.range_bias_std else 0.0
        )
        self.range_scale = (
            float(self.rng.normal(0.0, f.range_scale_std)) if f.range_scale_std else 0.0
        )

    def __repr__(self) -> str:
        return (
            f"SimulatedLidar({self.preset.name}, range_offset={self.range_offset:.4f} m,"
            f" range_scale={self.range_scale:.4f}, faults={self.faults})"
        )

    def scan(
        self,
        world: World,
        pose: ArrayLike,
        *,
        twist: tuple[float, float] = (0.0, 0.0),
        stamp: float = 0.0,
        mount_height: float = LIDAR_MOUNT_HEIGHT,
        frame_id: str = "laser",
    ) -> LaserScan:
        """One revolution that starts at ``stamp`` with the sensor at ``pose``.

        Parameters
        ----------
        world : World
        pose : array of shape (3,)
            Sensor pose x [m], y [m], theta [rad] at the first beam's time ``stamp``.
        twist : (v, w)
            The robot's forward speed [m/s] and turn rate [rad/s] during the revolution
            (only used with ``faults.motion_skew``); the sensor sits at the base origin.
        stamp : float
            Time [s] of the first beam (the LaserScan's stamp).
        mount_height : float
            Height [m] of the beam plane.

        Returns
        -------
        LaserScan
            ``n_beams`` readings (see the module docstring for +inf / -inf / NaN).
        """
        p = as_pose(pose)
        v = check_finite_scalar(twist[0], "twist[0] (v)")
        w = check_finite_scalar(twist[1], "twist[1] (w)")
        pr = self.preset
        f = self.faults
        gen = self.rng
        n = pr.n_beams
        scan_time = 1.0 / pr.scan_rate
        dt_beam = scan_time / n
        if f.motion_skew and (v != 0.0 or w != 0.0):
            bp = beam_poses(p, (v, w), np.arange(n) * dt_beam)
            origins: FloatArray = bp[:, :2]
            cast = bp[:, 2] + pr.angles
        else:
            origins = np.broadcast_to(p[:2], (n, 2))
            cast = p[2] + pr.angles
        if f.angle_jitter_bins > 0:
            cast = cast + gen.normal(0.0, f.angle_jitter_bins * pr.angle_increment, n)
        hits = raycast_nearest(world, origins, cast[:, None], min_height=mount_height)
        true = hits.ranges[:, 0].copy()
        mat = hits.materials[:, 0]
        cos_i = hits.cos_incidence[:, 0].copy()
        prim = hits.primitives[:, 0].copy()
        no_return = np.zeros(n, dtype=bool)
        glass = mat == MATERIAL_GLASS
        if not f.glass_opaque and np.any(glass):
            gi = np.flatnonzero(glass)
            inside = np.arccos(np.clip(cos_i[gi], 0.0, 1.0)) <= f.glass_reflect_angle
            u = gen.random((2, gi.size))
            reflect = inside & (u[0] < f.glass_reflect_prob)
            lost = ~reflect & (u[1] < f.glass_no_return_prob)
            through = gi[~reflect & ~lost]
            no_return[gi[lost]] = True
            if through.size:
                behind = raycast_nearest(
                    world,
                    origins[through],
                    cast[through][:, None],
                    min_height=mount_height,
                    skip_materials=(MATERIAL_GLASS,),
                )
                true[through] = behind.ranges[:, 0]
                mat = mat.copy()
                mat[through] = behind.materials[:, 0]
                cos_i[through] = behind.cos_incidence[:, 0]
                prim[through] = behind.primitives[:, 0]
        dark = (mat == MATERIAL_DARK) & np.isfinite(true) & ~no_return
        if math.isfinite(f.dark_range_fraction) and np.any(dark):
            r50 = f.dark_range_fraction * pr.range_max
            di = np.flatnonzero(dark)
            z = 2.0 * np.log(true[di] / r50) - np.log(np.maximum(cos_i[di], 1e-6))
            p_miss = ndtr(z / f.dark_spread)
            no_return[di[gen.random(di.size) < p_miss]] = True
        geo = true
        if f.mixed_pixel_prob > 0:
            geo = _mixed_pixels(true, prim, no_return, f, gen)
        ranges = geo.copy()
        hit = np.isfinite(geo)
        ranges[hit] += pr.sigma(geo[hit]) * gen.standard_normal(int(hit.sum()))
        if self.range_scale or self.range_offset:
            ranges[hit] = ranges[hit] * (1.0 + self.range_scale) + self.range_offset
        ranges[no_return] = np.inf
        ranges[ranges >= pr.range_max] = np.inf
        ranges[hit & ~no_return & (geo < pr.range_min)] = -np.inf
        rate = 1.0 - (1.0 - pr.dropout_rate) * (1.0 - f.dropout_rate)
        if rate > 0.0:
            ranges[gen.random(n) < rate] = np.nan
        return LaserScan(
            angle_min=pr.angle_min,
            angle_increment=pr.angle_increment,
            range_min=pr.range_min,
            range_max=pr.range_max,
            ranges=ranges,
            stamp=float(stamp),
            # without simulated skew the beams are all taken from ``pose``: say so (0), so that a
            # consumer that undoes skew leaves the scan as it is
            time_increment=dt_beam if f.motion_skew else 0.0,
            scan_time=scan_time,
            frame_id=frame_id,
        )


def _mixed_pixels(
    true: FloatArray,
    prim: NDArray[np.int64],
    no_return: NDArray[np.bool_],
    faults: LidarFaults,
    gen: np.random.Generator,
) -> FloatArray:
    """Ranges ``(N,)`` with mixed pixels at depth edges between beams i and i+1 (cyclic)."""
    ok = np.isfinite(true) & ~no_return
    nxt = np.roll(np.where(ok, true, 0.0), -1)
    edge = (
        ok
        & np.roll(ok, -1)
        & (prim != np.roll(prim, -1))
        & (np.abs(nxt - true) > faults.mixed_min_jump)
    )
    ei = np.flatnonzero(edge)
    out = true.copy()
    if ei.size == 0:
        return out
    u = gen.random((3, ei.size))
    ei = ei[u[0] < faults.mixed_pixel_prob]
    if ei.size == 0:
        return out
    j = np.where(u[1, : ei.size] < 0.5, ei, (ei + 1) % true.size)
    fg = np.minimum(true[ei], nxt[ei])
    bg = np.maximum(true[ei], nxt[ei])
    out[j] = fg + u[2, : ei.size] * (bg - fg)
    return out
