"""Odometry readings and the increment between two of them.

An odometry reading is the robot's pose in the odometry frame (``odom_from_base``) at a time.
Its absolute value drifts and means nothing; only the increment between two readings is used,
decomposed as in Thrun, Burgard and Fox, *Probabilistic Robotics* (2005), Table 5.6:
a first rotation ``rot1`` toward the direction of travel, a translation ``trans``, and a second
rotation ``rot2``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import DataFormatError
from symloc.geometry import angle_diff, relative, wrap_angle

__all__ = [
    "OdometryIncrement",
    "OdometryReading",
    "rot_trans_rot",
    "rot_trans_rot_to_pose",
    "twist_between",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True, eq=False)
class OdometryReading:
    """The robot's pose ``(3,)`` x [m], y [m], theta [rad] in the odometry frame at ``stamp`` [s]."""

    pose: FloatArray
    stamp: float = 0.0

    def __post_init__(self) -> None:
        try:
            p = np.array(self.pose, dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise DataFormatError("OdometryReading.pose: expected 3 numbers x, y, theta") from err
        if p.shape != (3,):
            raise DataFormatError(
                f"OdometryReading.pose: expected shape (3,) as x, y, theta; got {p.shape}"
            )
        if not np.all(np.isfinite(p)):
            raise DataFormatError(f"OdometryReading.pose: expected finite values, got {p}")
        if not math.isfinite(float(self.stamp)):
            raise DataFormatError(
                f"OdometryReading.stamp: expected a finite time, got {self.stamp}"
            )
        p[2] = wrap_angle(p[2])
        p.setflags(write=False)
        object.__setattr__(self, "pose", p)
        object.__setattr__(self, "stamp", float(self.stamp))


@dataclass(frozen=True, slots=True)
class OdometryIncrement:
    """Motion between two odometry readings.

    Attributes
    ----------
    delta : ndarray of shape (3,)
        The second pose in the first pose's frame: dx [m], dy [m], dtheta [rad].
    rot1, trans, rot2 : float
        The rotation-translation-rotation decomposition [rad, m, rad].
    dt : float
        Time between the readings [s].
    """

    delta: FloatArray
    rot1: float
    trans: float
    rot2: float
    dt: float

    @classmethod
    def between(cls, previous: OdometryReading, current: OdometryReading) -> OdometryIncrement:
        """The increment from ``previous`` to ``current``."""
        delta = relative(previous.pose, current.pose)
        r1, tr, r2 = rot_trans_rot(previous.pose, current.pose)
        return cls(delta, float(r1), float(tr), float(r2), current.stamp - previous.stamp)

    @property
    def rotation(self) -> float:
        """Total heading change [rad], wrapped."""
        return float(self.delta[2])


def rot_trans_rot(
    pose_prev: ArrayLike, pose_curr: ArrayLike, *, min_trans: float = 0.01
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Decompose motion between poses ``(..., 3)`` into rot1, trans, rot2 (Thrun Table 5.6).

    Below ``min_trans`` [m] the direction of travel is unobservable, so ``rot1`` is 0 and the
    whole turn goes into ``rot2`` (as ROS amcl does). Returns three arrays of shape ``(...)``.
    """
    a = np.asarray(pose_prev, dtype=np.float64)
    b = np.asarray(pose_curr, dtype=np.float64)
    dx = b[..., 0] - a[..., 0]
    dy = b[..., 1] - a[..., 1]
    trans = np.hypot(dx, dy)
    heading = np.arctan2(dy, dx)
    rot1 = np.where(trans < min_trans, 0.0, angle_diff(heading, a[..., 2]))
    rot2 = angle_diff(angle_diff(b[..., 2], a[..., 2]), rot1)
    return np.asarray(rot1), trans, np.asarray(rot2)


def rot_trans_rot_to_pose(
    pose: ArrayLike, rot1: ArrayLike, trans: ArrayLike, rot2: ArrayLike
) -> FloatArray:
    """Apply a rot1-trans-rot2 motion to poses ``(..., 3)``; the inverse of :func:`rot_trans_rot`."""
    p = np.asarray(pose, dtype=np.float64)
    r1 = np.asarray(rot1, dtype=np.float64)
    tr = np.asarray(trans, dtype=np.float64)
    r2 = np.asarray(rot2, dtype=np.float64)
    heading = p[..., 2] + r1
    x = p[..., 0] + tr * np.cos(heading)
    y = p[..., 1] + tr * np.sin(heading)
    return np.stack([x, y, wrap_angle(heading + r2)], axis=-1)


def twist_between(
    earlier: OdometryReading, later: OdometryReading, *, max_gap: float = 0.5
) -> tuple[float, float]:
    """The robot's forward speed [m/s] and turn rate [rad/s] between two odometry readings.

    ``(0, 0)`` when the readings are not in time order or more than ``max_gap`` [s] apart
    (no recent motion to extrapolate). Backward motion gives a negative speed.
    """
    gap = float(later.stamp) - float(earlier.stamp)
    if not (0.0 < gap <= max_gap):
        return 0.0, 0.0
    d = relative(earlier.pose, later.pose)
    dist = math.hypot(float(d[0]), float(d[1]))
    v = (dist if d[0] >= 0.0 else -dist) / gap
    return v, float(d[2]) / gap
