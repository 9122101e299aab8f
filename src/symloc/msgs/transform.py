"""geometry_msgs/TransformStamped and tf2_msgs/TFMessage -> :class:`StampedTransform`.

A transform is kept as a (4, 4) homogeneous ``parent_from_child`` matrix with its stamp [s] and
frames (leading slashes dropped, as tf2 does). Both the bag reader (:mod:`symloc.io.rosbag`, the
``tf`` and ``tf_static`` kinds) and the node's TF (:mod:`symloc.ros.tf`) use it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import DataFormatError
from symloc.msgs.fields import field, finite_field, stamp_from_seconds
from symloc.msgs.header import header_frame, header_stamp

__all__ = [
    "StampedTransform",
    "tf_message_fields",
    "transform_fields",
    "transform_from_msg",
    "transforms_from_msg",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class StampedTransform:
    """``parent_from_child`` as a (4, 4) homogeneous matrix, at ``stamp`` [s]."""

    parent: str
    child: str
    stamp: float
    matrix: FloatArray


def _quaternion_matrix(x: float, y: float, z: float, w: float, where: str) -> FloatArray:
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(n) or n < 1e-9:
        raise DataFormatError(f"{where}: expected a non-zero finite quaternion, got {x, y, z, w}")
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def transform_from_msg(msg: Any, where: str = "TransformStamped") -> StampedTransform:
    """A geometry_msgs/TransformStamped (rclpy, rosbags or look-alike) as a
    :class:`StampedTransform`.

    Raises
    ------
    DataFormatError
        A field is missing or not finite, a frame is empty, or the rotation is a zero
        quaternion.
    """
    parent = header_frame(msg, where)
    child = field(msg, "child_frame_id", where)
    if not isinstance(child, str):
        raise DataFormatError(f"{where}.child_frame_id: expected a string, got {child!r}")
    child = child.lstrip("/")
    if not parent or not child:
        raise DataFormatError(f"{where}: expected non-empty frames, got {parent!r} -> {child!r}")
    t = [finite_field(msg, f"transform.translation.{c}", where) for c in "xyz"]
    q = [finite_field(msg, f"transform.rotation.{c}", where) for c in "xyzw"]
    m = np.eye(4)
    m[:3, :3] = _quaternion_matrix(q[0], q[1], q[2], q[3], f"{where}.transform.rotation")
    m[:3, 3] = t
    return StampedTransform(parent, child, header_stamp(msg, where), m)


def transforms_from_msg(msg: Any) -> list[StampedTransform]:
    """The transforms of a tf2_msgs/TFMessage (``/tf`` or ``/tf_static``)."""
    items = field(msg, "transforms", "TFMessage")
    try:
        seq = list(items)
    except TypeError as err:
        raise DataFormatError("TFMessage.transforms: expected a sequence") from err
    return [transform_from_msg(t, f"TFMessage.transforms[{i}]") for i, t in enumerate(seq)]


def transform_fields(pose: ArrayLike, *, stamp: float, parent: str, child: str) -> dict[str, Any]:
    """A geometry_msgs/TransformStamped field dict of a planar ``parent_from_child`` pose."""
    x, y, th = (float(v) for v in np.asarray(pose, dtype=np.float64).reshape(3))
    return {
        "header": {"stamp": stamp_from_seconds(stamp), "frame_id": parent},
        "child_frame_id": child,
        "transform": {
            "translation": {"x": x, "y": y, "z": 0.0},
            "rotation": {"x": 0.0, "y": 0.0, "z": math.sin(th / 2), "w": math.cos(th / 2)},
        },
    }


def tf_message_fields(transforms: Iterable[dict[str, Any]]) -> dict[str, Any]:
    """A tf2_msgs/TFMessage field dict."""
    return {"transforms": list(transforms)}
