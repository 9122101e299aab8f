"""``LaserScan``, a mirror of sensor_msgs/LaserScan, and its conversion to points (eq. 1-2).

Semantics of one reading ``r``, as REP 117 and sensor_msgs define them:

- ``NaN``, ``-inf`` or ``r < range_min``: **invalid** (the sensor measured nothing usable);
- ``+inf`` or ``r >= range_max``: **no return** (nothing within range along that beam);
- otherwise **valid**: a point at distance ``r`` along the beam.

Beam ``i`` points at ``angle_min + i * angle_increment`` [rad] in the sensor frame, counter-
clockwise from the sensor's +x axis.

Precision: sensor_msgs/LaserScan carries its ranges, angles, range limits and times as float32;
:class:`LaserScan` holds float64. :func:`message_precision` rounds a scan to what the message
can carry, so a scan read from a text log and the same scan read back from a bag are one scan
(:func:`symloc.io.carmen.read_carmen` reads a log's scans that way).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import DataFormatError

__all__ = [
    "MESSAGE_FLOAT",
    "LaserScan",
    "ScanPoints",
    "deskew",
    "message_precision",
    "mirror",
    "sensor_twist",
]

FloatArray = NDArray[np.float64]

#: The float type of sensor_msgs/LaserScan's ranges, intensities, angles, range limits and
#: times (``float32`` in the message definition).
MESSAGE_FLOAT = np.float32


@lru_cache(maxsize=64)
def _beam_angles(angle_min: float, angle_increment: float, n: int) -> FloatArray:
    """Read-only beam angles ``(n,)`` [rad], one array shared by every scan of the same
    geometry (a log's thousands of scans would otherwise each hold a copy)."""
    angles: FloatArray = angle_min + angle_increment * np.arange(n, dtype=np.float64)
    angles.setflags(write=False)
    return angles


def _finite_field(value: object, name: str) -> float:
    try:
        out = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError) as err:
        raise DataFormatError(f"LaserScan.{name}: expected a number, got {value!r}") from err
    if not math.isfinite(out):
        raise DataFormatError(f"LaserScan.{name}: expected a finite number, got {out}")
    return out


@dataclass(frozen=True, slots=True)
class ScanPoints:
    """The valid readings of a scan as Cartesian points in the sensor frame.

    Attributes
    ----------
    points : ndarray of shape (M, 2)
        x, y [m] of each valid reading (eq. 1-2 of the paper).
    angles : ndarray of shape (M,)
        Beam angle [rad] of each point.
    ranges : ndarray of shape (M,)
        Range [m] of each point.
    indices : ndarray of shape (M,)
        Index of each point's beam in the original scan.
    n_invalid : int
        Readings dropped as invalid (NaN, -inf, below range_min).
    n_no_return : int
        Readings dropped as no return (+inf or at/above range_max).
    """

    points: FloatArray
    angles: FloatArray
    ranges: FloatArray
    indices: NDArray[np.intp]
    n_invalid: int
    n_no_return: int

    @property
    def n_dropped(self) -> int:
        """Total readings that did not become points."""
        return self.n_invalid + self.n_no_return


@dataclass(frozen=True, slots=True, eq=False)
class LaserScan:
    """One laser scan, field for field as sensor_msgs/LaserScan.

    Parameters
    ----------
    angle_min : float
        Angle of the first beam [rad].
    angle_increment : float
        Angle between beams [rad], > 0 (counter-clockwise scanners; reverse a clockwise
        scan's ranges and negate its angles before building it).
    range_min, range_max : float
        Valid range interval [m], ``0 <= range_min < range_max``.
    ranges : array of shape (N,)
        Measured ranges [m]; see the module docstring for NaN / inf semantics.
    intensities : array of shape (N,), optional
        Device-specific intensities; empty or of the same length as ``ranges``.
    stamp : float
        Acquisition time of the first beam [s].
    time_increment, scan_time : float
        Time between beams and between scans [s], as in the ROS message.
    frame_id : str
        Name of the sensor frame.
    """

    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: FloatArray
    intensities: FloatArray | None = None
    stamp: float = 0.0
    time_increment: float = 0.0
    scan_time: float = 0.0
    frame_id: str = "laser"
    _angles: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for name in ("angle_min", "angle_increment", "range_min", "range_max", "stamp"):
            set_(self, name, _finite_field(getattr(self, name), name))
        for name in ("time_increment", "scan_time"):
            set_(self, name, _finite_field(getattr(self, name), name))
        if self.angle_increment <= 0.0:
            raise DataFormatError(
                f"LaserScan.angle_increment: expected > 0 rad, got {self.angle_increment}"
                " (reverse the ranges of a clockwise scanner)"
            )
        if self.range_min < 0.0:
            raise DataFormatError(f"LaserScan.range_min: expected >= 0 m, got {self.range_min}")
        if self.range_max <= self.range_min:
            raise DataFormatError(
                f"LaserScan.range_max: expected > range_min ({self.range_min} m),"
                f" got {self.range_max}"
            )
        try:
            ranges = np.array(self.ranges, dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise DataFormatError("LaserScan.ranges: expected an array of numbers") from err
        if ranges.ndim != 1:
            raise DataFormatError(f"LaserScan.ranges: expected a 1-D array, got {ranges.shape}")
        if ranges.size == 0:
            raise DataFormatError("LaserScan.ranges: expected at least one reading, got none")
        if self.angle_increment * (ranges.size - 1) > 2.0 * math.pi + 1e-6:
            raise DataFormatError(
                f"LaserScan.angle_increment: {ranges.size} beams x {self.angle_increment} rad"
                " span more than one revolution"
            )
        ranges.setflags(write=False)
        set_(self, "ranges", ranges)
        if self.intensities is not None:
            inten = np.array(self.intensities, dtype=np.float64)
            if inten.size and inten.shape != ranges.shape:
                raise DataFormatError(
                    f"LaserScan.intensities: expected {ranges.size} values like ranges,"
                    f" got shape {inten.shape}"
                )
            inten.setflags(write=False)
            set_(self, "intensities", inten if inten.size else None)
        set_(self, "_angles", _beam_angles(self.angle_min, self.angle_increment, ranges.size))

    @classmethod
    def from_angle_range(
        cls,
        angle_min: float,
        angle_max: float,
        ranges: ArrayLike,
        *,
        range_min: float,
        range_max: float,
        **kwargs: object,
    ) -> LaserScan:
        """Build a scan whose beams span [angle_min, angle_max] evenly, as a ROS driver does."""
        r = np.asarray(ranges, dtype=np.float64)
        if r.ndim != 1 or r.size < 2:
            raise DataFormatError("LaserScan.ranges: expected a 1-D array of at least 2 values")
        inc = (float(angle_max) - float(angle_min)) / (r.size - 1)
        return cls(float(angle_min), inc, range_min, range_max, r, **kwargs)  # type: ignore[arg-type]

    def __len__(self) -> int:
        return int(self.ranges.size)

    @property
    def angle_max(self) -> float:
        """Angle of the last beam [rad]."""
        return self.angle_min + self.angle_increment * (self.ranges.size - 1)

    @property
    def angles(self) -> FloatArray:
        """Beam angles ``(N,)`` [rad] in the sensor frame (read-only)."""
        return self._angles

    @property
    def invalid_mask(self) -> NDArray[np.bool_]:
        """``(N,)`` True where the reading is NaN, -inf or below range_min."""
        r = self.ranges
        with np.errstate(invalid="ignore"):
            return np.isnan(r) | (r < self.range_min)

    @property
    def no_return_mask(self) -> NDArray[np.bool_]:
        """``(N,)`` True where the reading is +inf or at/above range_max."""
        with np.errstate(invalid="ignore"):
            return self.ranges >= self.range_max

    @property
    def valid_mask(self) -> NDArray[np.bool_]:
        """``(N,)`` True where the reading is a point within [range_min, range_max)."""
        r = self.ranges
        with np.errstate(invalid="ignore"):
            return (r >= self.range_min) & (r < self.range_max)

    def to_points(self) -> ScanPoints:
        """Convert the valid readings to Cartesian points (the paper's eq. 1-2).

        ``x_i = r_i cos(phi_i)``, ``y_i = r_i sin(phi_i)``; invalid and no-return readings are
        dropped and counted in the result.
        """
        valid = self.valid_mask
        idx = np.flatnonzero(valid)
        r = self.ranges[idx]
        a = self._angles[idx]
        pts = np.column_stack([r * np.cos(a), r * np.sin(a)])
        n_no_return = int(np.count_nonzero(self.no_return_mask))
        n_invalid = int(self.ranges.size - idx.size - n_no_return)
        return ScanPoints(pts, a, r, idx, n_invalid, n_no_return)

    def with_ranges(self, ranges: ArrayLike, *, stamp: float | None = None) -> LaserScan:
        """A copy of this scan's geometry with new ranges (and optionally a new stamp)."""
        return LaserScan(
            self.angle_min,
            self.angle_increment,
            self.range_min,
            self.range_max,
            np.asarray(ranges, dtype=np.float64),
            None,
            self.stamp if stamp is None else stamp,
            self.time_increment,
            self.scan_time,
            self.frame_id,
        )


def deskew(scan: LaserScan, v: float, w: float, *, vy: float = 0.0) -> LaserScan:
    """The scan as the sensor would have taken it standing still at its stamp (first beam).

    A spinning lidar takes its beams one after the other over ``scan_time``: beam ``i`` at
    ``stamp + i * time_increment``. A robot moving at ``v`` [m/s], turning at ``w`` [rad/s]
    (constant over the sweep; e.g. from the last two odometry readings,
    :func:`symloc.odometry.twist_between`) shifts and turns later beams. Rotation is undone
    exactly: beam ``i`` points at ``angle_min + i (angle_increment + w time_increment)``.
    Translation (the sensor moved along an arc) is undone along each beam, to first order:
    the range gains the sensor's displacement projected on the beam's direction (at 0.3 m/s
    and 10 Hz the lateral remainder is at most 3 cm x sin(bearing), against up to 3 cm
    uncorrected). Beams that would wrap past one revolution are dropped; invalid and
    no-return readings keep their values. A scan without ``time_increment``, or a robot
    standing still, comes back unchanged.

    ``v`` and ``vy`` are the sensor's own velocity along its x and y axes (a laser mounted off
    the robot's centre also moves sideways when the robot turns, see
    :func:`sensor_twist`). A negative ``time_increment`` means the beams were taken in reverse
    order (a mirrored scan of an upside-down laser, :func:`mirror`): beam ``i`` at
    ``stamp + (n - 1 - i) |time_increment|``, the stamp still being the earliest beam's time.
    """
    dt = scan.time_increment
    moving = v != 0.0 or vy != 0.0 or w != 0.0
    if dt == 0.0 or not moving or not all(math.isfinite(x) for x in (v, vy, w)):
        return scan
    inc = scan.angle_increment + w * dt
    if inc <= 0.0:
        return scan
    n = min(len(scan), math.floor(2.0 * math.pi / inc + 1e-9) + 1)
    steps = np.arange(n) - (len(scan) - 1 if dt < 0.0 else 0)
    t = steps * dt
    th = w * t
    if abs(w) > 1e-9:
        x = (v * np.sin(th) - vy * (1.0 - np.cos(th))) / w
        y = (v * (1.0 - np.cos(th)) + vy * np.sin(th)) / w
    else:
        x = v * t
        y = vy * t
    angle_min = scan.angle_min + w * float(t[0])
    a = angle_min + inc * np.arange(n)
    r = scan.ranges[:n]
    with np.errstate(invalid="ignore"):
        point = (r >= scan.range_min) & (r < scan.range_max)
    out = r.copy()
    out[point] = r[point] + x[point] * np.cos(a[point]) + y[point] * np.sin(a[point])
    inten = None if scan.intensities is None else scan.intensities[:n]
    return LaserScan(
        angle_min,
        inc,
        scan.range_min,
        scan.range_max,
        out,
        inten,
        scan.stamp,
        scan.time_increment,
        scan.scan_time,
        scan.frame_id,
    )


_MESSAGE_MAX = float(np.finfo(MESSAGE_FLOAT).max)
_MESSAGE_TINY = float(np.finfo(MESSAGE_FLOAT).smallest_subnormal)


def _at_message_float(x: float) -> float:
    """``x`` rounded to float32, kept finite and of the same sign (a value beyond float32's
    range becomes its largest or smallest magnitude instead of inf or 0)."""
    if abs(x) > _MESSAGE_MAX:
        return math.copysign(_MESSAGE_MAX, x)
    out = float(MESSAGE_FLOAT(x))
    if out == 0.0 and x != 0.0:
        return math.copysign(_MESSAGE_TINY, x)
    return out


def message_precision(scan: LaserScan) -> LaserScan:
    """``scan`` as a sensor_msgs/LaserScan carries it: ranges, intensities, ``angle_min``,
    ``angle_increment``, ``range_min``, ``range_max``, ``time_increment`` and ``scan_time``
    rounded to float32 (and held as float64 again); the stamp (a ROS time of seconds and
    nanoseconds) and the frame are unchanged.

    Idempotent: a scan that already holds float32 values (one read from a bag) comes back as
    the same object, and a scan written to a bag and read back is this function's result
    bit for bit. Rounding moves a range by at most 2^-24 of itself (0.5 um at 8 m) and a beam
    angle by at most 1e-7 rad.

    Parameters
    ----------
    scan : LaserScan
        Any scan; its ranges (N,) [m] and angles [rad] as float64.

    Returns
    -------
    LaserScan
        The same geometry and readings at float32 precision (N,) [m].
    """
    scalars = (
        scan.angle_min,
        scan.angle_increment,
        scan.range_min,
        scan.range_max,
        scan.time_increment,
        scan.scan_time,
    )
    given = scan.intensities
    with np.errstate(over="ignore"):  # a range beyond float32 becomes inf: no return, as in a bag
        ranges = scan.ranges.astype(MESSAGE_FLOAT)
        inten = None if given is None else given.astype(MESSAGE_FLOAT)
    with np.errstate(invalid="ignore"):
        same = (
            all(_at_message_float(v) == v for v in scalars)
            and np.array_equal(ranges, scan.ranges, equal_nan=True)
            and (inten is None or given is None or np.array_equal(inten, given, equal_nan=True))
        )
    if same:
        return scan
    a_min, a_inc, r_min, r_max, t_inc, t_scan = (_at_message_float(v) for v in scalars)
    return LaserScan(
        a_min,
        a_inc,
        r_min,
        r_max,
        ranges.astype(np.float64),
        None if inten is None else inten.astype(np.float64),
        scan.stamp,
        t_inc,
        t_scan,
        scan.frame_id,
    )


def mirror(scan: LaserScan) -> LaserScan:
    """The scan of a laser mounted upside down, as a laser with its z axis up sees it.

    Turned over (a roll of 180 degrees), the laser's counter-clockwise sweep is clockwise seen
    from above: beam ``i`` at angle ``a_i`` of the laser points at ``-a_i`` in the upright
    frame. The result lists the same readings in reverse order from ``-angle_max`` with the
    same positive increment; its ``time_increment`` is negated (the beams were taken in
    reverse order, which :func:`deskew` understands) and its stamp is unchanged.
    """
    n = len(scan)
    inten = None if scan.intensities is None else scan.intensities[::-1].copy()
    return LaserScan(
        -(scan.angle_min + (n - 1) * scan.angle_increment),
        scan.angle_increment,
        scan.range_min,
        scan.range_max,
        scan.ranges[::-1].copy(),
        inten,
        scan.stamp,
        -scan.time_increment,
        scan.scan_time,
        scan.frame_id,
    )


def sensor_twist(v: float, w: float, laser_pose: ArrayLike) -> tuple[float, float, float]:
    """The velocity ``(vx, vy, w)`` of a sensor mounted at ``laser_pose`` on a moving robot.

    The robot moves forward at ``v`` [m/s] and turns at ``w`` [rad/s]; the sensor sits at
    ``laser_pose`` (3,) x [m], y [m], yaw [rad] in the robot frame. A sensor off the centre
    also moves sideways while the robot turns; ``vx``, ``vy`` are along the sensor's own
    axes (what :func:`deskew` takes), ``w`` is unchanged.
    """
    px, py, yaw = (float(c) for c in np.asarray(laser_pose, dtype=np.float64).reshape(3))
    bx, by = v - w * py, w * px
    c, s = math.cos(yaw), math.sin(yaw)
    return c * bx + s * by, -s * bx + c * by, w
