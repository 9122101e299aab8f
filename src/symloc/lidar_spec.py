"""Data-sheet figures of 2D lidars: beam layout, range limits and range noise.

A robot's symmetry judgement derives its tolerances from these figures
(:meth:`symloc.symmetry.SymmetryConfig.from_lidar`), and the simulator
(:func:`symloc.sim.lidar.simulate_scan`) draws its noise from them.

Noise model
-----------
A data sheet states accuracy as a band: "+-10 mm" or "+-3.5 % of the distance". We map such a
band to a zero-mean Gaussian with ``sigma = sigma_fraction * band``; the default
``sigma_fraction = 0.5`` reads the band as the 2-sigma (about 95 %) interval, the usual meaning of
a "typical" accuracy figure. A simulator's own stated standard deviation (Gazebo's ``stddev``)
is used as is (``sigma_fraction = 1``). The band itself is piecewise:
``band(r) = accuracy_abs`` for ``r < accuracy_break`` and ``accuracy_rel * r`` beyond.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError

__all__ = ["LDS01", "PAPER_15M", "PRESETS", "RPLIDAR_A2", "LidarPreset"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LidarPreset:
    """A 360-degree 2D lidar as its data sheet describes it.

    Parameters
    ----------
    name : str
        Short name (used by the CLI).
    n_beams : int
        Beams per revolution, evenly spaced over 360 degrees starting at ``angle_min``.
    range_min, range_max : float
        Measurable range [m].
    accuracy_abs : float
        Accuracy band [m] below ``accuracy_break``.
    accuracy_break : float
        Range [m] where the band switches from absolute to relative (``inf``: always absolute).
    accuracy_rel : float
        Accuracy band as a fraction of the range at and beyond ``accuracy_break``.
    sigma_fraction : float
        Gaussian sigma as a fraction of the band (see the module docstring), in (0, 1].
    dropout_rate : float
        Probability in [0, 1) that a beam returns NaN (invalid).
    scan_rate : float
        Revolutions per second [Hz] (sets ``scan_time`` and ``time_increment``).
    angle_min : float
        Angle of the first beam [rad].
    source : str
        Where the figures come from.
    """

    name: str
    n_beams: int
    range_min: float
    range_max: float
    accuracy_abs: float
    accuracy_break: float
    accuracy_rel: float
    sigma_fraction: float = 0.5
    dropout_rate: float = 0.0
    scan_rate: float = 10.0
    angle_min: float = 0.0
    source: str = ""

    def __post_init__(self) -> None:
        if int(self.n_beams) != self.n_beams or self.n_beams < 3:
            raise ConfigurationError(
                f"LidarPreset.n_beams: expected an integer >= 3, got {self.n_beams}"
            )
        if not (0.0 <= self.range_min < self.range_max and math.isfinite(self.range_max)):
            raise ConfigurationError(
                "LidarPreset range: expected 0 <= range_min < range_max < inf, got"
                f" range_min={self.range_min}, range_max={self.range_max}"
            )
        if not (self.accuracy_abs >= 0 and self.accuracy_rel >= 0 and self.accuracy_break >= 0):
            raise ConfigurationError(
                "LidarPreset accuracy: accuracy_abs, accuracy_rel and accuracy_break must be"
                f" >= 0, got {self.accuracy_abs}, {self.accuracy_rel}, {self.accuracy_break}"
            )
        if not 0.0 < self.sigma_fraction <= 1.0:
            raise ConfigurationError(
                f"LidarPreset.sigma_fraction: expected a value in (0, 1], got {self.sigma_fraction}"
            )
        if not 0.0 <= self.dropout_rate < 1.0:
            raise ConfigurationError(
                f"LidarPreset.dropout_rate: expected a value in [0, 1), got {self.dropout_rate}"
            )
        if not (self.scan_rate > 0 and math.isfinite(self.scan_rate)):
            raise ConfigurationError(
                f"LidarPreset.scan_rate: expected a finite value > 0 Hz, got {self.scan_rate}"
            )
        if not math.isfinite(self.angle_min):
            raise ConfigurationError("LidarPreset.angle_min: expected a finite angle [rad]")

    @property
    def angle_increment(self) -> float:
        """Angle between beams [rad]: 2 pi / n_beams."""
        return 2.0 * math.pi / self.n_beams

    @property
    def angles(self) -> FloatArray:
        """Beam angles ``(n_beams,)`` [rad] in the sensor frame."""
        return np.asarray(self.angle_min + self.angle_increment * np.arange(self.n_beams))

    def accuracy(self, ranges: ArrayLike) -> FloatArray:
        """The data sheet's accuracy band [m] at each range ``(N,)`` [m]."""
        r = np.asarray(ranges, dtype=np.float64)
        out = np.where(r < self.accuracy_break, self.accuracy_abs, self.accuracy_rel * r)
        return np.asarray(out, dtype=np.float64)

    def sigma(self, ranges: ArrayLike) -> FloatArray:
        """Gaussian range-noise standard deviation [m] at each range ``(N,)`` [m]."""
        return self.sigma_fraction * self.accuracy(ranges)

    def with_(self, **changes: object) -> LidarPreset:
        """A copy with some fields changed (validated again), e.g. ``dropout_rate=0.05``."""
        return replace(self, **changes)  # type: ignore[arg-type]


LDS01 = LidarPreset(
    name="lds01",
    n_beams=360,
    range_min=0.12,
    range_max=3.5,
    accuracy_abs=0.010,
    accuracy_break=0.5,
    accuracy_rel=0.035,
    sigma_fraction=0.5,
    scan_rate=5.0,
    source=(
        "ROBOTIS e-Manual, TurtleBot3 Appendix LDS-01 (HLS-LFCD2), "
        "https://emanual.robotis.com/docs/en/platform/turtlebot3/appendix_lds_01/ : range "
        "120-3500 mm, angular resolution 1 deg, 300 rpm (5 Hz), +-10 mm (120-499 mm) and "
        "+-3.5 % (500-3500 mm). As we recall that page, these two rows are its distance "
        "*precision* (repeatability) and it also lists an accuracy (bias) of +-15 mm / +-5.0 %; "
        "a zero-mean Gaussian models the precision only. Not re-checked online for this build"
    ),
)
"""TurtleBot3 LDS-01: 360 beams, 1 degree, 0.12-3.5 m, +-10 mm (< 0.5 m) / +-3.5 % (>= 0.5 m).

Sigma = half the band: 5 mm below 0.5 m, 1.75 % of the range above."""

RPLIDAR_A2 = LidarPreset(
    name="rplidar_a2",
    n_beams=800,
    range_min=0.15,
    range_max=16.0,
    accuracy_abs=0.0,
    accuracy_break=0.0,
    accuracy_rel=0.01,
    sigma_fraction=0.5,
    scan_rate=10.0,
    source=(
        "SLAMTEC RPLIDAR A2 Introduction and Datasheet (models A2M7/A2M8, rev 1.x): "
        "range 0.15 m minimum, sample frequency 8000 Hz at a typical 10 Hz scan rate "
        "(0.45 deg angular resolution, so 800 points per revolution), distance resolution "
        "< 0.5 mm below 1.5 m and < 1 % of the distance over the whole range. The paper "
        "(Sec. 5.2) gives the 16 m measuring radius. Assumption: the data sheet gives no separate "
        "accuracy figure, so we use its '< 1 % of the distance' as the accuracy band for all "
        "ranges and ignore the < 0.5 mm figure (a quantisation step, not an error bound)"
    ),
)
"""RPLIDAR A2 as used in the paper: 800 beams (0.45 deg), 0.15-16 m, band 1 % of range, sigma
0.5 % of range."""

PAPER_15M = LidarPreset(
    name="paper_15m",
    n_beams=360,
    range_min=0.12,
    range_max=15.0,
    accuracy_abs=0.01,
    accuracy_break=math.inf,
    accuracy_rel=0.0,
    sigma_fraction=1.0,
    scan_rate=5.0,
    source=(
        "The paper's Gazebo scanner (Sec. 5.1): TurtleBot3 burger lds_lfcd_sensor with the "
        "scanning radius set to 15 m. turtlebot3_description/urdf/turtlebot3_burger.gazebo.xacro "
        "declares 360 samples, range 0.12-3.5 m (here 15 m as the paper sets it), 5 Hz, and "
        "Gaussian noise with mean 0 and stddev 0.01 m, used directly as sigma"
    ),
)
"""The paper's simulated 15 m scanner: 360 beams, 0.12-15 m, Gaussian sigma 10 mm."""

PRESETS: dict[str, LidarPreset] = {p.name: p for p in (LDS01, RPLIDAR_A2, PAPER_15M)}
"""Presets by name."""
