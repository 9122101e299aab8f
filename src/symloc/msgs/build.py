"""Build ROS messages from nested field dicts, for rclpy or for rosbags.

The ``*_to_fields`` conversions in :mod:`symloc.msgs` return plain nested dicts with the ROS
field names (no ROS import needed). Two builders turn such a dict into a real message:

- :func:`build_rclpy` for a live node (message classes of the ``*_msgs`` Python packages);
- :func:`build_rosbags` for writing bags (the message dataclasses of a ``rosbags`` typestore).

Fields not given take their ROS defaults (0, "", empty sequences, default sub-messages), so
one dict serves ROS 1 (``Header.seq``) and ROS 2 alike.
"""

from __future__ import annotations

import array
import importlib
from collections.abc import Mapping
from typing import Any

import numpy as np

from symloc.errors import DataFormatError

__all__ = ["build_rclpy", "build_rosbags"]

_RCLPY_TYPECODES = {
    "float": "f",
    "double": "d",
    "uint8": "B",
    "octet": "B",
    "int8": "b",
    "int16": "h",
    "uint16": "H",
    "int32": "i",
    "uint32": "I",
    "int64": "q",
    "uint64": "Q",
}

_ROSBAGS_DTYPES = {
    "bool": np.bool_,
    "byte": np.uint8,
    "char": np.uint8,
    "int8": np.int8,
    "uint8": np.uint8,
    "int16": np.int16,
    "uint16": np.uint16,
    "int32": np.int32,
    "uint32": np.uint32,
    "int64": np.int64,
    "uint64": np.uint64,
    "float32": np.float32,
    "float64": np.float64,
}


def _rclpy_class(name: str) -> type:
    """``geometry_msgs/Pose`` or ``geometry_msgs/msg/Pose`` -> the rclpy message class."""
    parts = name.split("/")
    module = importlib.import_module(f"{parts[0]}.msg")
    cls: type = getattr(module, parts[-1])
    return cls


def build_rclpy(cls: type, fields: Mapping[str, Any]) -> Any:
    """An rclpy message of class ``cls`` with ``fields`` (nested dicts for sub-messages).

    Raises
    ------
    DataFormatError
        A key is not a field of the message, or a value does not fit its field.
    """
    msg = cls()
    types: dict[str, str] = cls.get_fields_and_field_types()  # type: ignore[attr-defined]
    name = cls.__name__
    for key, value in fields.items():
        ftype = types.get(key)
        if ftype is None:
            raise DataFormatError(f"{name}.{key}: no such field (fields: {sorted(types)})")
        try:
            setattr(msg, key, _rclpy_value(msg, key, ftype, value))
        except (AssertionError, TypeError, ValueError) as err:
            raise DataFormatError(f"{name}.{key}: value does not fit {ftype}: {err}") from err
    return msg


def _rclpy_value(msg: Any, key: str, ftype: str, value: Any) -> Any:
    if isinstance(value, Mapping):
        return build_rclpy(type(getattr(msg, key)), value)
    if ftype.startswith("sequence<") and ftype.endswith(">"):
        inner = ftype[len("sequence<") : -1].split(",")[0]
        if "/" in inner:
            sub = _rclpy_class(inner)
            return [build_rclpy(sub, v) if isinstance(v, Mapping) else v for v in value]
        code = _RCLPY_TYPECODES.get(inner)
        if code is not None:
            arr = np.asarray(value, dtype=np.dtype(code))
            return array.array(code, arr.tobytes())
        return list(value)
    if ftype.endswith("]") and "[" in ftype:  # fixed-size array, stored as ndarray
        base = ftype[: ftype.index("[")]
        code = _RCLPY_TYPECODES.get(base)
        return np.asarray(value, dtype=np.dtype(code)) if code else list(value)
    if ftype in ("float", "double"):
        return float(value)
    if ftype == "boolean":
        return bool(value)
    if ftype == "string":
        return str(value)
    if ftype == "octet":
        return value if isinstance(value, bytes) else bytes([int(value)])
    if ftype in _RCLPY_TYPECODES or ftype in ("int64", "uint64"):
        return int(value)
    return value


def build_rosbags(typestore: Any, msgtype: str, fields: Mapping[str, Any]) -> Any:
    """A rosbags message dataclass of ``msgtype`` (e.g. ``sensor_msgs/msg/LaserScan``).

    ``typestore`` is a :class:`rosbags.typesys.store.Typestore`; fields missing from
    ``fields`` take their defaults.

    Raises
    ------
    DataFormatError
        ``msgtype`` is unknown to the typestore or a key is not one of its fields.
    """
    if msgtype not in typestore.fielddefs:
        raise DataFormatError(f"{msgtype}: message type not in the typestore")
    _, defs = typestore.fielddefs[msgtype]
    known = {fname for fname, _ in defs}
    extra = set(fields) - known
    if extra:
        raise DataFormatError(f"{msgtype}.{sorted(extra)[0]}: no such field")
    kwargs = {}
    for fname, desc in defs:
        try:
            kwargs[fname] = _rosbags_value(typestore, desc, fields.get(fname))
        except (TypeError, ValueError) as err:
            raise DataFormatError(f"{msgtype}.{fname}: value does not fit: {err}") from err
    return typestore.types[msgtype](**kwargs)


def _rosbags_value(typestore: Any, desc: Any, value: Any) -> Any:
    kind, detail = desc
    kind = int(kind)
    if kind == 1:  # BASE
        base = detail[0]
        if base == "string":
            return "" if value is None else str(value)
        if base in ("float32", "float64"):
            return 0.0 if value is None else float(value)
        if base == "bool":
            return bool(value)
        return 0 if value is None else int(value)
    if kind == 2:  # NAME
        return build_rosbags(typestore, detail, value or {})
    # ARRAY (3) or SEQUENCE (4): detail = (element desc, length)
    elem, length = detail
    ekind, edetail = elem
    if int(ekind) == 2:
        items = list(value or [])
        if int(kind) == 3 and not items:
            items = [{}] * length
        return [build_rosbags(typestore, edetail, v) for v in items]
    base = edetail[0]
    if base == "string":
        return [str(v) for v in (value or [""] * (length if int(kind) == 3 else 0))]
    dtype = _ROSBAGS_DTYPES[base]
    if value is None:
        return np.zeros(length if int(kind) == 3 else 0, dtype=dtype)
    if isinstance(value, (bytes, bytearray, memoryview)):
        return np.frombuffer(value, dtype=np.uint8).astype(dtype)
    arr: np.ndarray[Any, Any] = np.asarray(value, dtype=dtype).reshape(-1)
    if int(kind) == 3 and arr.size != length:
        raise ValueError(f"expected {length} values, got {arr.size}")
    return arr
