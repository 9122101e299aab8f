"""Choosing and cleaning the beams a sensor model uses, as nav2_amcl does.

nav2_amcl (``laserReceived``) limits the range to ``laser_max_range`` / ``laser_min_range``
when they are set, turns every reading at or below the minimum range into a max-range reading,
and each sensor model then walks the beams with the integer step
``(range_count - 1) // (max_beams - 1)``. The likelihood-field models skip max-range (no
return) readings; the beam model scores them with ``z_max``. NaN and -inf readings carry no
information and are dropped (counted).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.scan import LaserScan

__all__ = ["BeamSet", "select_beams"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class BeamSet:
    """The beams of one scan a sensor model scores.

    Attributes
    ----------
    ranges : ndarray of shape (B,)
        Range [m] of each sub-sampled, non-NaN beam; no-return beams hold ``range_max``.
    angles : ndarray of shape (B,)
        Bearing [rad] of each beam in the laser frame.
    hit : ndarray of shape (B,), bool
        True where the beam returned (range < range_max).
    beam_index : ndarray of shape (B,)
        Position of the beam in the sub-sampled sequence (nav2's ``beam_ind``).
    n_steps : int
        Number of beams in the sub-sampled sequence (before dropping NaNs).
    range_max : float
        Effective maximum range [m] (``min(scan.range_max, laser_max_range)``).
    n_no_return, n_invalid : int
        Sub-sampled beams that did not return / were NaN or -inf.
    """

    ranges: FloatArray
    angles: FloatArray
    hit: NDArray[np.bool_]
    beam_index: NDArray[np.intp]
    n_steps: int
    range_max: float
    n_no_return: int
    n_invalid: int

    @property
    def n_hits(self) -> int:
        """Number of beams that returned."""
        return int(np.count_nonzero(self.hit))


def select_beams(
    scan: LaserScan,
    max_beams: int,
    *,
    laser_max_range: float = 100.0,
    laser_min_range: float = -1.0,
) -> BeamSet:
    """Sub-sample and clean a scan's beams the way nav2_amcl does.

    Parameters
    ----------
    scan : LaserScan
    max_beams : int
        nav2's ``max_beams`` (>= 2); step ``(n - 1) // (max_beams - 1)`` (at least 1).
    laser_max_range, laser_min_range : float
        nav2's overrides [m]; a value <= 0 keeps the scan's own limit.
    """
    if not isinstance(scan, LaserScan):
        raise ConfigurationError(f"scan: expected a LaserScan, got {type(scan).__name__}")
    if max_beams < 2:
        raise ConfigurationError(f"max_beams: expected an integer >= 2, got {max_beams}")
    range_max = scan.range_max
    if laser_max_range > 0.0:
        range_max = min(range_max, laser_max_range)
    range_min = scan.range_min
    if laser_min_range > 0.0:
        range_min = max(range_min, laser_min_range)
    n = len(scan)
    step = max((n - 1) // (max_beams - 1), 1)
    idx = np.arange(0, n, step)
    r = scan.ranges[idx].astype(np.float64)
    a = scan.angles[idx]
    nan = np.isnan(r) | (r == -np.inf)
    r = np.where(nan, range_max, r)
    r = np.where(r <= range_min, range_max, r)  # nav2: below min range -> max range
    r = np.minimum(r, range_max)
    keep = ~nan
    hit = r < range_max
    return BeamSet(
        ranges=r[keep],
        angles=a[keep],
        hit=hit[keep],
        beam_index=np.flatnonzero(keep),
        n_steps=int(idx.size),
        range_max=float(range_max),
        n_no_return=int(np.count_nonzero(~hit[keep])),
        n_invalid=int(np.count_nonzero(nan)),
    )
