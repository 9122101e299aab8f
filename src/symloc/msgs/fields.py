"""Field access shared by every ROS message conversion.

The conversions read messages only through attribute names, so they work on rclpy messages,
on the message dataclasses that ``rosbags`` deserialises, and on any stand-in object with the
same field names. A missing or malformed field raises :class:`~symloc.errors.DataFormatError`
naming the field as ``Type.path.to.field``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import DataFormatError

__all__ = [
    "field",
    "finite_field",
    "numeric_array",
    "quaternion_from_yaw",
    "stamp_from_seconds",
    "stamp_seconds",
    "yaw_from_quaternion",
]

_MISSING = object()


def field(msg: Any, path: str, where: str) -> Any:
    """Return ``msg.<path>`` (dotted), raising DataFormatError naming ``where.path`` if absent."""
    obj = msg
    for part in path.split("."):
        obj = getattr(obj, part, _MISSING)
        if obj is _MISSING:
            raise DataFormatError(f"{where}.{path}: field is missing")
    return obj


def finite_field(msg: Any, path: str, where: str) -> float:
    """Return ``msg.<path>`` as a finite float, naming the field when it is not one."""
    value = field(msg, path, where)
    try:
        out = float(value)
    except (TypeError, ValueError) as err:
        raise DataFormatError(f"{where}.{path}: expected a number, got {value!r}") from err
    if not math.isfinite(out):
        raise DataFormatError(f"{where}.{path}: expected a finite number, got {out}")
    return out


def numeric_array(value: Any, name: str, dtype: type = np.float64) -> NDArray[Any]:
    """Convert a message sequence (list, ``array.array``, bytes, ndarray) to a 1-D array."""
    try:
        if isinstance(value, (bytes, bytearray, memoryview)):
            return np.frombuffer(value, dtype=np.uint8).astype(dtype, copy=False)
        arr: NDArray[Any] = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as err:
        raise DataFormatError(f"{name}: expected a sequence of numbers") from err
    if arr.ndim != 1:
        raise DataFormatError(f"{name}: expected a 1-D sequence, got shape {arr.shape}")
    return arr


def stamp_seconds(stamp: Any, where: str) -> float:
    """Seconds since the epoch of a ROS time (``sec``/``nanosec`` or ROS 1 ``secs``/``nsecs``)."""
    sec = getattr(stamp, "sec", getattr(stamp, "secs", _MISSING))
    nsec = getattr(stamp, "nanosec", getattr(stamp, "nsecs", _MISSING))
    if sec is _MISSING or nsec is _MISSING:
        raise DataFormatError(f"{where}: expected a time with sec and nanosec, got {stamp!r}")
    try:
        return float(sec) + 1e-9 * float(nsec)  # type: ignore[arg-type]
    except (TypeError, ValueError) as err:
        raise DataFormatError(f"{where}: sec/nanosec are not numbers: {stamp!r}") from err


def stamp_from_seconds(t: float) -> dict[str, int]:
    """A ``builtin_interfaces/Time`` as a field dict from seconds (rounded to the nanosecond)."""
    ns = round(float(t) * 1e9)
    if ns < 0:
        raise DataFormatError(f"stamp: expected a time >= 0 s, got {t}")
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def yaw_from_quaternion(q: Any, where: str) -> float:
    """Yaw [rad] of a quaternion (x, y, z, w), which must be finite and not zero.

    The quaternion is normalised first; roll and pitch are ignored (a planar robot).
    """
    x, y, z, w = (finite_field(q, k, where) for k in ("x", "y", "z", "w"))
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n < 1e-9:
        raise DataFormatError(f"{where}: expected a unit quaternion, got all zeros")
    x, y, z, w = x / n, y / n, z / n, w / n
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quaternion_from_yaw(yaw: float) -> dict[str, float]:
    """A ``geometry_msgs/Quaternion`` field dict for a rotation of ``yaw`` [rad] about z."""
    h = 0.5 * float(yaw)
    return {"x": 0.0, "y": 0.0, "z": math.sin(h), "w": math.cos(h)}
