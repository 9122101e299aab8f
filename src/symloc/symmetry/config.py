"""Settings of the symmetry judgement, in metres, derived from the sensor's range noise."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_in_range, check_positive
from symloc.errors import ConfigurationError

__all__ = ["SymmetryConfig"]


@dataclass(frozen=True, slots=True)
class SymmetryConfig:
    """How strict the symmetry judgement is; every tolerance follows from the range noise.

    The range noise of one beam at range ``r`` is modelled as a Gaussian with standard deviation
    ``sigma(r) = hypot(range_sigma, range_sigma_relative * r)`` (a data sheet gives both forms).
    "Equal" in the judgement means "equal within ``k_sigma`` standard deviations", where the
    standard deviation of a derived quantity (a line, a corner, a centroid) is propagated from
    ``sigma(r)``, plus ``model_tolerance`` for what the noise model leaves out (range
    quantisation, wall thickness, the corners cut off between two sparse points).

    Parameters
    ----------
    range_sigma : float
        Range noise [m] independent of range (> 0). Default 0.01 m (a 15 m scanner's data
        sheet figure, as the paper's Gazebo sensor).
    range_sigma_relative : float
        Range noise as a fraction of the range (>= 0), e.g. 0.035 for the LDS-01's 3.5 %.
    k_sigma : float
        How many standard deviations still count as "equal" (> 0). Default 5: with ~1000
        independent residuals per scan, a 5-sigma bound is exceeded by chance in fewer than one
        scan in a thousand.
    tolerance : float or None
        A fixed point-to-line tolerance [m] that replaces ``k_sigma * sigma(r)`` (the paper's
        epsilon); ``None`` (default) derives it from the noise.
    model_tolerance : float
        Slack [m] added to every derived tolerance (>= 0). Default 0.005 m.
    min_points : int
        Fewer valid points than this give the verdict "unknown" (>= 3).
    max_dropout_beams : int
        Longest run of no-return beams bridged as a dropout on a continuous wall (>= 0); longer
        runs open the contour (a door, a wall beyond range).
    max_blind_beams : int
        Longest run of missing beams of any kind (invalid readings: sensor dropouts, NaN)
        bridged on a continuous wall (>= max_dropout_beams). Invalid readings are the sensor's
        fault, not the room's, so more of them are bridged; whether the walls on both sides of
        the gap still meet is checked by the corner test.
    min_line_points : int
        A line with fewer points is clutter, not a wall (>= 2).
    max_clutter_points : int
        How many points may lie on such clutter before the room counts as not symmetric (>= 0).
    max_polygon_sides : int
        Largest number of walls of a polygonal room (>= 3).
    min_angle_tolerance : float
        Smallest tolerance [rad] on angles (parallel walls, right angles), > 0.
    max_door_width : float
        A gap in a wall up to this wide [m] is reported as an opening (door) that breaks the
        symmetry, rather than as a wall beyond range (> 0).
    min_door_width : float
        A gap in a straight wall narrower than this [m] is a run of sensor dropouts (a dark,
        shiny or glass patch that returned nothing), not a door (>= 0, < max_door_width).
        Default 0.5 m, below the narrowest doorways.
    partial_view : bool
        Judge scans whose field of view is under 360 degrees for the one symmetric pattern a
        partial view can show: a hallway (two long parallel walls on either side whose far
        ends are beyond range). The part behind the sensor is not seen and is *assumed* to
        continue the hallway; the report's reason says so. Default False: a partial view gives
        "unknown".
    """

    range_sigma: float = 0.01
    range_sigma_relative: float = 0.0
    k_sigma: float = 5.0
    tolerance: float | None = None
    model_tolerance: float = 0.005
    min_points: int = 12
    max_dropout_beams: int = 2
    max_blind_beams: int = 10
    min_line_points: int = 3
    max_clutter_points: int = 0
    max_polygon_sides: int = 16
    min_angle_tolerance: float = math.radians(0.5)
    max_door_width: float = 2.0
    min_door_width: float = 0.5
    partial_view: bool = False

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "range_sigma", check_positive(self.range_sigma, "range_sigma"))
        set_(
            self,
            "range_sigma_relative",
            check_in_range(self.range_sigma_relative, "range_sigma_relative", 0.0, 1.0),
        )
        set_(self, "k_sigma", check_positive(self.k_sigma, "k_sigma"))
        if self.tolerance is not None:
            set_(self, "tolerance", check_positive(self.tolerance, "tolerance"))
        set_(
            self,
            "model_tolerance",
            check_positive(self.model_tolerance, "model_tolerance", allow_zero=True),
        )
        for name, low in (
            ("min_points", 3),
            ("max_dropout_beams", 0),
            ("max_blind_beams", 0),
            ("min_line_points", 2),
            ("max_clutter_points", 0),
            ("max_polygon_sides", 3),
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ConfigurationError(f"{name}: expected an integer, got {value!r}")
            if value < low:
                raise ConfigurationError(f"{name}: expected an integer >= {low}, got {value}")
            set_(self, name, int(value))
        if self.max_blind_beams < self.max_dropout_beams:
            raise ConfigurationError(
                f"max_blind_beams: expected >= max_dropout_beams ({self.max_dropout_beams}),"
                f" got {self.max_blind_beams}"
            )
        set_(
            self,
            "min_angle_tolerance",
            check_in_range(self.min_angle_tolerance, "min_angle_tolerance", 1e-9, math.pi / 4),
        )
        set_(self, "max_door_width", check_positive(self.max_door_width, "max_door_width"))
        set_(
            self,
            "min_door_width",
            check_positive(self.min_door_width, "min_door_width", allow_zero=True),
        )
        if self.min_door_width >= self.max_door_width:
            raise ConfigurationError(
                f"min_door_width: expected < max_door_width ({self.max_door_width} m), got"
                f" {self.min_door_width}"
            )
        if not isinstance(self.partial_view, (bool, np.bool_)):
            raise ConfigurationError(f"partial_view: expected a bool, got {self.partial_view!r}")
        set_(self, "partial_view", bool(self.partial_view))

    @classmethod
    def from_noise(cls, sigma: float, relative: float = 0.0, **overrides: Any) -> SymmetryConfig:
        """A config whose tolerances follow from a sensor's range noise.

        Parameters
        ----------
        sigma : float
            Range noise [m] (standard deviation, independent of range).
        relative : float
            Range noise as a fraction of the range.
        **overrides
            Any other field.
        """
        return cls(range_sigma=sigma, range_sigma_relative=relative, **overrides)

    @classmethod
    def from_lidar(cls, preset: Any, **overrides: Any) -> SymmetryConfig:
        """A config for a :class:`symloc.lidar_spec.LidarPreset`.

        The preset's piecewise noise (``sigma_fraction * accuracy_abs`` below
        ``accuracy_break``, ``sigma_fraction * accuracy_rel * r`` beyond) is bounded from above
        by ``hypot(range_sigma, range_sigma_relative * r)`` with the two pieces as the two
        terms. A preset without an absolute figure gets 1 mm (range resolution).
        """
        try:
            frac = float(preset.sigma_fraction)
            acc_abs = float(preset.accuracy_abs)
            acc_rel = float(preset.accuracy_rel)
            brk = float(preset.accuracy_break)
        except AttributeError as err:
            raise ConfigurationError(
                "preset: expected a LidarPreset with sigma_fraction, accuracy_abs, accuracy_rel"
                f" and accuracy_break, got {preset!r}"
            ) from err
        sigma = frac * acc_abs if brk > 0 else 0.0
        relative = frac * acc_rel if math.isfinite(brk) else 0.0
        return cls(range_sigma=max(sigma, 1e-3), range_sigma_relative=relative, **overrides)

    def sigma(self, ranges: ArrayLike) -> NDArray[np.float64]:
        """Range noise standard deviation [m] at each range [m]."""
        r = np.asarray(ranges, dtype=np.float64)
        if self.range_sigma_relative == 0.0:
            return np.full(r.shape, self.range_sigma)  # == hypot(range_sigma, 0)
        return np.hypot(self.range_sigma, self.range_sigma_relative * r)

    def sigma_and_tolerance(
        self, ranges: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`sigma` and :meth:`point_tolerance` at each range [m], computed together."""
        sig = self.sigma(ranges)
        if self.tolerance is not None:
            return sig, np.full(sig.shape, self.tolerance)
        return sig, self.k_sigma * sig + self.model_tolerance

    def point_tolerance(self, ranges: ArrayLike) -> NDArray[np.float64]:
        """Largest distance [m] of a point at each range from its wall: ``k sigma(r) + slack``."""
        r = np.asarray(ranges, dtype=np.float64)
        if self.tolerance is not None:
            return np.full(r.shape, self.tolerance)
        return self.k_sigma * self.sigma(r) + self.model_tolerance
