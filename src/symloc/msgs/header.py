"""``std_msgs/Header``: stamp and frame of a message, and the header field dict."""

from __future__ import annotations

from typing import Any

from symloc.errors import DataFormatError
from symloc.msgs.fields import field, stamp_from_seconds, stamp_seconds

__all__ = ["header_fields", "header_frame", "header_stamp"]


def header_stamp(msg: Any, where: str) -> float:
    """``msg.header.stamp`` in seconds."""
    return stamp_seconds(field(msg, "header.stamp", where), f"{where}.header.stamp")


def header_frame(msg: Any, where: str) -> str:
    """``msg.header.frame_id`` (a string; a leading ``/`` of ROS 1 frames is stripped)."""
    frame = field(msg, "header.frame_id", where)
    if not isinstance(frame, str):
        raise DataFormatError(f"{where}.header.frame_id: expected a string, got {frame!r}")
    return frame.lstrip("/")


def header_fields(stamp: float, frame_id: str) -> dict[str, Any]:
    """A ``std_msgs/Header`` field dict."""
    return {"stamp": stamp_from_seconds(stamp), "frame_id": str(frame_id)}
