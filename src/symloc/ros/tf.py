"""TF for the node, without tf2: the laser's mount, odometry from ``/tf``, and ``map -> odom``.

nav2 talks to its localizer through TF. This module does what nav2_amcl does with tf2, on
plain arrays, so that it runs (and is tested) without rclpy:

- :class:`TransformTree` keeps the transforms of ``/tf_static`` (the robot's geometry) and the
  newest of each transform on ``/tf``, and looks up ``target_from_source`` across the tree
  (``base_footprint -> base_link -> laser``).
- :func:`laser_mount` turns ``base_from_laser`` into the planar pose the localizer needs and
  says whether the laser is mounted upside down (its z axis points down); such a scan is
  mirrored (:func:`symloc.scan.mirror`) before it reaches the localizer, as nav2_amcl
  computes its beam angles in the base frame.
- :func:`odometry_from_transform` reads ``odom -> base`` from a ``/tf`` transform (through
  static links when the odometry's child frame is not the base frame itself).
- :class:`MapToOdom` decides what to broadcast as ``map -> odom`` after each scan.

**What is broadcast.** ``map -> odom`` is ``map_from_base * inverse(odom_from_base)``: the pose
the claim gate confirmed at a scan and the odometry at the scan's stamp, stamped with the scan
time plus ``transform_tolerance`` (so that tf2 lookups up to that time succeed while odometry
carries the robot).

**While the pose is held** it is sent again at every scan, as nav2_amcl re-sends its transform
between filter updates: with a newly confirmed pose, or re-stamped for this scan from the last
confirmed pose carried by odometry (the same ``map -> odom``) when the claim gate only withheld
the claim, or the scan was late or unusable (``Localizer.holds_pose``). **It is withdrawn** (not
re-stamped: it ages, tf2 lookups past its stamp fail, and nav2 stops planning and following
paths instead of driving on a pose nobody vouches for) only when the localizer concludes that
the pose is wrong or lost: a withdrawn claim, ambiguity, deciding, lost, a kidnapping, a global
re-initialisation or a new operator pose; it resumes with the next confirmed pose.
``symloc/status`` says which (its ``map_to_odom`` value). Before the first pose is earned
nothing is ever sent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.geometry import compose, inverse, wrap_angle
from symloc.localizer import Estimate, Status
from symloc.msgs.transform import (
    StampedTransform,
    tf_message_fields,
    transform_fields,
    transform_from_msg,
    transforms_from_msg,
)
from symloc.odometry import OdometryReading

__all__ = [
    "MAX_TILT",
    "LaserMount",
    "MapToOdom",
    "StampedTransform",
    "TransformTree",
    "laser_mount",
    "map_from_odom",
    "matrix_from_planar",
    "odometry_from_transform",
    "planar",
    "tf_message_fields",
    "transform_fields",
    "transform_from_msg",
    "transforms_from_msg",
]

FloatArray = NDArray[np.float64]

#: Largest angle [rad] between the laser's scan plane and the floor that is still treated as
#: level (a 2D localizer assumes a level scan; more tilt is reported by :func:`laser_mount`).
MAX_TILT = math.radians(10.0)


def planar(matrix: ArrayLike) -> FloatArray:
    """``(x, y, yaw)`` of a (4, 4) transform: its translation in the plane and the heading of
    its x axis projected on the plane."""
    m = np.asarray(matrix, dtype=np.float64)
    return np.array([m[0, 3], m[1, 3], math.atan2(m[1, 0], m[0, 0])])


def matrix_from_planar(pose: ArrayLike) -> FloatArray:
    """The (4, 4) transform of a planar pose ``(x, y, yaw)``."""
    x, y, th = (float(v) for v in np.asarray(pose, dtype=np.float64).reshape(3))
    c, s = math.cos(th), math.sin(th)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[0, 3], m[1, 3] = x, y
    return m


class TransformTree:
    """The frames of ``/tf_static`` and ``/tf``: each child's parent and the newest transform.

    A frame has one parent, as in tf2; a transform that gives a frame a second parent replaces
    the first (and is reported by :meth:`add`'s return value).
    """

    def __init__(self) -> None:
        self._edges: dict[str, StampedTransform] = {}
        self._static: set[str] = set()

    def add(self, t: StampedTransform, *, static: bool) -> bool:
        """Store ``t``; False when an older dynamic transform was ignored."""
        old = self._edges.get(t.child)
        if (
            old is not None
            and not static
            and t.child not in self._static
            and old.parent == t.parent
            and t.stamp < old.stamp
        ):
            return False
        self._edges[t.child] = t
        if static:
            self._static.add(t.child)
        else:
            self._static.discard(t.child)
        return True

    def __contains__(self, frame: str) -> bool:
        return frame in self._edges or any(e.parent == frame for e in self._edges.values())

    def _chain(self, frame: str) -> list[str]:
        chain = [frame]
        seen = {frame}
        while chain[-1] in self._edges:
            parent = self._edges[chain[-1]].parent
            if parent in seen:  # a loop: tf2 would refuse it as well
                break
            chain.append(parent)
            seen.add(parent)
        return chain

    def _root_from(self, chain: list[str]) -> FloatArray:
        m = np.eye(4)
        for frame in reversed(chain[:-1]):
            m = m @ self._edges[frame].matrix
        return m

    def lookup(self, target: str, source: str) -> FloatArray | None:
        """``target_from_source`` (4, 4) through the tree, or None when they are not linked."""
        if target == source:
            return np.eye(4)
        a, b = self._chain(target), self._chain(source)
        common = next((f for f in a if f in set(b)), None)
        if common is None:
            return None
        a = a[: a.index(common) + 1]
        b = b[: b.index(common) + 1]
        common_from_target = self._root_from(a)
        common_from_source = self._root_from(b)
        return np.asarray(np.linalg.inv(common_from_target) @ common_from_source)


@dataclass(frozen=True)
class LaserMount:
    """How the laser sits on the robot.

    ``pose`` (3,): ``base_from_laser`` in the plane (x [m], y [m], yaw [rad] of the laser's x
    axis), for the upright laser frame of a mirrored scan when ``upside_down``; ``tilt``
    [rad]: the angle between the scan plane and the floor.
    """

    pose: FloatArray
    upside_down: bool = False
    tilt: float = 0.0

    @property
    def level(self) -> bool:
        """True when the scan plane is within :data:`MAX_TILT` of the floor."""
        return self.tilt <= MAX_TILT


def laser_mount(base_from_laser: ArrayLike) -> LaserMount:
    """The planar mount of a laser from its (4, 4) ``base_from_laser`` transform.

    A laser whose z axis points down (rolled or pitched by 180 degrees) sweeps clockwise seen
    from above: its scans are mirrored (:func:`symloc.scan.mirror`) and its pose is that of the
    laser frame turned back upright by a roll of 180 degrees (the x axis is kept).
    """
    m = np.asarray(base_from_laser, dtype=np.float64)
    z = m[:3, 2]
    upside_down = bool(z[2] < 0.0)
    tilt = math.acos(min(1.0, abs(float(z[2]))))
    return LaserMount(planar(m), upside_down, tilt)


def odometry_from_transform(
    t: StampedTransform, tree: TransformTree, *, odom_frame: str, base_frame: str
) -> OdometryReading | None:
    """``odom -> base`` at ``t.stamp`` from a ``/tf`` transform ``odom -> child`` (None when
    ``t`` is not one, or when ``child`` is not statically linked to ``base_frame``)."""
    if t.parent != odom_frame:
        return None
    if t.child == base_frame:
        odom_from_base = t.matrix
    else:
        child_from_base = tree.lookup(t.child, base_frame)
        if child_from_base is None:
            return None
        odom_from_base = t.matrix @ child_from_base
    return OdometryReading(planar(odom_from_base), t.stamp)


def map_from_odom(map_from_base: ArrayLike, odom_from_base: ArrayLike) -> FloatArray:
    """``map_from_odom`` (3,) from the robot's pose in the map and in the odometry frame."""
    m = compose(np.asarray(map_from_base, dtype=np.float64), inverse(odom_from_base))
    m[2] = wrap_angle(m[2])
    return m


class MapToOdom:
    """What to broadcast as ``map -> odom`` after each scan (the policy of the module docstring).

    Parameters
    ----------
    global_frame, odom_frame : str
    tolerance : float
        ``transform_tolerance`` [s]: a transform is stamped this far after its scan.
    enabled : bool
        nav2's ``tf_broadcast``; False never sends anything.
    """

    def __init__(
        self, *, global_frame: str, odom_frame: str, tolerance: float, enabled: bool = True
    ) -> None:
        self.global_frame = global_frame
        self.odom_frame = odom_frame
        self.tolerance = float(tolerance)
        self.enabled = bool(enabled)
        #: the last transform sent: (pose (3,), the stamp it carries)
        self.last: tuple[FloatArray, float] | None = None
        #: the stamp of the scan whose confirmed pose the last transform comes from
        self.confirmed_at: float | None = None
        #: True while the last transform may be re-sent (the pose is held, see :meth:`step`)
        self.holding = False

    def _message(self, pose: FloatArray, valid_until: float) -> dict[str, Any]:
        self.last = (pose, valid_until)
        return tf_message_fields(
            [
                transform_fields(
                    pose, stamp=valid_until, parent=self.global_frame, child=self.odom_frame
                )
            ]
        )

    def step(
        self, est: Estimate, stamp: float, odom_pose: ArrayLike, *, holds: bool = False
    ) -> dict[str, Any] | None:
        """The TFMessage field dict to send after the scan at ``stamp`` (None: send nothing).

        A confirmed pose (status tracking) gives a new transform. ``holds`` (the localizer
        still vouches for its last confirmed pose: a claim withheld at this scan, not withdrawn)
        re-sends the last transform stamped for this scan, as nav2_amcl does between filter
        updates: the last confirmed pose carried by odometry. Otherwise nothing is sent and
        nothing will be re-sent until a pose is confirmed again.
        """
        if not self.enabled:
            return None
        if est.status is Status.TRACKING and est.pose is not None:
            self.holding = True
            self.confirmed_at = float(stamp)
            return self._message(map_from_odom(est.pose, odom_pose), float(stamp) + self.tolerance)
        if holds:
            return self.resend(stamp)
        self.holding = False
        return None

    def resend(self, stamp: float) -> dict[str, Any] | None:
        """The last transform again, stamped ``stamp`` + ``transform_tolerance``, while a pose
        is held (None otherwise, or when that would not be newer than what was sent)."""
        if not self.enabled or not self.holding or self.last is None:
            return None
        valid_until = float(stamp) + self.tolerance
        if valid_until <= self.last[1]:
            return None
        return self._message(self.last[0], valid_until)

    def forget(self) -> None:
        """Stop re-sending (the pose was replaced or forgotten); the last transform ages."""
        self.holding = False

    def describe(self, stamp: float) -> str:
        """One line for the status: what the broadcast ``map -> odom`` is at ``stamp``."""
        if not self.enabled:
            return "not broadcast (tf_broadcast false)"
        if self.last is None:
            return "never sent (no pose earned yet)"
        valid_until = self.last[1]
        fresh = valid_until - self.tolerance >= stamp - 1e-9
        if fresh and self.confirmed_at is not None and self.confirmed_at >= stamp - 1e-9:
            return f"sent, stamped {valid_until:.3f}"
        if fresh and self.holding:
            return (
                f"re-sent, stamped {valid_until:.3f}, from the pose confirmed at the scan at"
                f" {self.confirmed_at:.3f} carried by odometry"
            )
        return f"not updated since the scan at {valid_until - self.tolerance:.3f} (stamped {valid_until:.3f})"
