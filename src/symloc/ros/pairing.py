"""Scans paired with the odometry at their own stamp, as nav2_amcl pairs them.

nav2_amcl puts every scan through a tf2 message filter: the scan waits until the
``odom -> base`` transform at its stamp can be looked up, up to ``transform_tolerance``, and is
dropped after that. symloc does the same without tf2:

- :class:`OdometryBuffer` keeps the recent odometry readings and answers the pose at any stamp
  it covers (interpolated between the two readings around it);
- :class:`ScanPairing` holds the scans newer than the newest odometry and releases each one,
  in order, once the odometry reaches its stamp (:class:`Paired`), or gives it up when it has
  waited too long (:class:`Unpaired`, with the reason the node counts under ``dropped/``).

Both are pure bookkeeping: the node (:class:`~symloc.ros.core.NodeCore`) turns a released
scan into a localizer step or a counted drop.
"""

from __future__ import annotations

import bisect
from collections import deque
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import angle_diff, wrap_angle
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan

__all__ = [
    "MAX_HELD_SCANS",
    "NO_ODOM_AT_STAMP",
    "OdometryBuffer",
    "Paired",
    "ScanPairing",
    "Unpaired",
]

FloatArray = NDArray[np.float64]

#: Scans held at most while they wait for the odometry at their stamp (nav2_amcl's tf2
#: message filter queue).
MAX_HELD_SCANS = 10
#: Why a held scan was dropped (``dropped/<reason>`` in the status).
NO_ODOM_AT_STAMP = "scan: no odometry at its stamp within transform_tolerance"


@dataclass
class OdometryBuffer:
    """Recent odometry readings, oldest first: ``stamps`` [s] and ``poses`` (3,) each."""

    stamps: list[float] = field(default_factory=list)
    poses: list[FloatArray] = field(default_factory=list)

    def add(self, reading: OdometryReading, max_age: float) -> bool:
        """Append ``reading`` and forget readings older than ``max_age`` [s] before it; False
        (and nothing kept) when it is older than the newest reading."""
        if self.stamps and reading.stamp < self.stamps[-1]:
            return False
        self.stamps.append(reading.stamp)
        self.poses.append(np.asarray(reading.pose, dtype=np.float64))
        cut = bisect.bisect_left(self.stamps, reading.stamp - max_age)
        if cut > 0:
            del self.stamps[:cut], self.poses[:cut]
        return True

    def forget_after(self, t: float) -> None:
        """Drop the readings stamped after ``t`` (they were outliers)."""
        cut = bisect.bisect_right(self.stamps, t)
        del self.stamps[cut:], self.poses[cut:]

    @property
    def newest_stamp(self) -> float | None:
        """The stamp [s] of the newest reading (None when empty)."""
        return self.stamps[-1] if self.stamps else None

    def at(self, t: float, tolerance: float) -> OdometryReading | str:
        """The reading at ``t`` (exact, interpolated, or the newest within ``tolerance`` [s]),
        or why there is none."""
        if not self.stamps:
            return "no odometry yet"
        if t > self.stamps[-1]:
            if t - self.stamps[-1] > tolerance:
                return "no odometry within transform_tolerance"
            return OdometryReading(self.poses[-1], self.stamps[-1])
        i = bisect.bisect_left(self.stamps, t)
        if self.stamps[i] == t:
            return OdometryReading(self.poses[i], t)
        if i == 0:
            return "older than the odometry history"
        t0, t1 = self.stamps[i - 1], self.stamps[i]
        p0, p1 = self.poses[i - 1], self.poses[i]
        f = (t - t0) / (t1 - t0)
        xy = p0[:2] + f * (p1[:2] - p0[:2])
        th = wrap_angle(p0[2] + f * float(angle_diff(p1[2], p0[2])))
        return OdometryReading(np.array([xy[0], xy[1], th]), t)


@dataclass(frozen=True)
class Paired:
    """A released scan and the odometry at its stamp."""

    scan: LaserScan
    odom: OdometryReading


@dataclass(frozen=True)
class Unpaired:
    """A released scan that gets no odometry: ``reason`` (counted) and ``detail`` (logged)."""

    scan: LaserScan
    reason: str
    detail: str


class ScanPairing:
    """Scans waiting for the odometry at their stamp, released in arrival order.

    Parameters
    ----------
    max_held : int
        More scans than this waiting: the oldest is given up (nav2_amcl's filter queue).
    """

    def __init__(self, max_held: int = MAX_HELD_SCANS) -> None:
        self.max_held = max_held
        #: (scan, arrival time on the node's clock [s] or None)
        self._held: deque[tuple[LaserScan, float | None]] = deque()

    def __len__(self) -> int:
        return len(self._held)

    @property
    def newest_stamp(self) -> float | None:
        """The stamp [s] of the newest held scan (None when none waits)."""
        return self._held[-1][0].stamp if self._held else None

    def hold(self, scan: LaserScan, now: float | None) -> None:
        """Let ``scan``, arrived at ``now`` [s] (None: unknown), wait for its odometry."""
        self._held.append((scan, now))

    def release(
        self, odom: OdometryBuffer, tolerance: float, now: float | None
    ) -> list[Paired | Unpaired]:
        """The held scans that can be answered at ``now``, in order: those the odometry now
        covers (paired at their stamp), and those that waited more than ``tolerance`` [s]
        (``now`` minus their arrival, or a newer scan stamped that much later) or that
        overflow ``max_held`` (unpaired)."""
        out: list[Paired | Unpaired] = []
        while self._held:
            scan, arrived = self._held[0]
            newest = odom.newest_stamp
            if newest is not None and scan.stamp <= newest:
                self._held.popleft()
                reading = odom.at(scan.stamp, tolerance)
                if isinstance(reading, str):
                    out.append(Unpaired(scan, f"scan: {reading}", f"scan at {scan.stamp:.3f} s"))
                else:
                    out.append(Paired(scan, reading))
                continue
            waited = None if now is None or arrived is None else now - arrived
            newer = self._held[-1][0].stamp - scan.stamp
            if (
                (waited is not None and waited > tolerance)
                or newer > tolerance
                or len(self._held) > self.max_held
            ):
                self._held.popleft()
                have = f"{newest:.3f} s" if newest is not None else "none"
                how_long = (
                    f" {waited:.2f} s" if waited is not None else f" for {newer:.2f} s of scans"
                )
                out.append(
                    Unpaired(
                        scan,
                        NO_ODOM_AT_STAMP,
                        f"scan at {scan.stamp:.3f} s waited{how_long}; newest odometry {have}",
                    )
                )
                continue
            break
        return out
