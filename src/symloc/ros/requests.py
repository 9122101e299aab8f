"""Read the node's status back into symloc types: for drivers written in Python.

A robot-side driver (or the integration test's simulator) subscribes ``symloc/status`` and
gets the localizer's :class:`~symloc.localizer.Status` and
:class:`~symloc.localizer.Request` from it with :func:`status_from_msg`; the request target and
angle are in the robot's base frame at the stamp of the scan the status answers.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import DataFormatError
from symloc.localizer import Request, RequestKind, Status
from symloc.msgs.fields import field

__all__ = ["NodeStatus", "status_from_msg"]


@dataclass(frozen=True, slots=True)
class NodeStatus:
    """One ``symloc/status`` message, parsed.

    Attributes
    ----------
    status : Status
    request : Request or None
    stamp : float
        Stamp [s] of the scan this status answers.
    pose : ndarray of shape (3,) or None
        The earned pose (map frame) when tracking.
    candidates : ndarray of shape (K, 4)
        x, y, theta, weight of each candidate pose.
    reason : str
    values : dict
        Every key / value of the message.
    axis_pose : ndarray of shape (3,) or None
        Status ``axis`` (heading known, position along a corridor not): the middle of the
        segment with the decided heading (map frame). Not a pose to drive on.
    axis_ends : ndarray of shape (2, 2) or None
        Status ``axis``: the segment's ends [m] (map frame).
    """

    status: Status
    request: Request | None
    stamp: float
    pose: NDArray[np.float64] | None
    candidates: NDArray[np.float64]
    reason: str
    values: dict[str, str]
    axis_pose: NDArray[np.float64] | None = None
    axis_ends: NDArray[np.float64] | None = None


def _floats(text: str, key: str) -> NDArray[np.float64]:
    try:
        return np.array([float(v) for v in text.split()], dtype=np.float64)
    except ValueError as err:
        raise DataFormatError(
            f"DiagnosticStatus value {key!r}: expected numbers, got {text!r}"
        ) from err


def status_from_msg(msg: Any) -> NodeStatus:
    """Parse a ``diagnostic_msgs/DiagnosticArray`` published by the symloc node.

    Raises
    ------
    DataFormatError
        The message is not a symloc status (no ``symloc: localization`` entry, unknown status).
    """
    entries = [
        s for s in field(msg, "status", "DiagnosticArray") if s.name == "symloc: localization"
    ]
    if not entries:
        raise DataFormatError("DiagnosticArray.status: no 'symloc: localization' entry")
    values = {kv.key: kv.value for kv in entries[0].values}
    try:
        status = Status(values.get("status", ""))
    except ValueError as err:
        raise DataFormatError(f"status: unknown value {values.get('status')!r}") from err
    kind = values.get("request", "")
    request = None
    if kind:
        try:
            rk = RequestKind(kind)
        except ValueError as err:
            raise DataFormatError(f"request: unknown kind {kind!r}") from err
        target = (
            _floats(values["request_target"], "request_target")
            if "request_target" in values
            else None
        )
        angle = float(values["request_angle"]) if "request_angle" in values else None
        request = Request(rk, target=target, angle=angle)
    n = int(values.get("candidates", "0") or 0)
    cands = np.array(
        [_floats(values[f"candidate_{i}"], f"candidate_{i}") for i in range(n)]
    ).reshape(-1, 4)
    pose = _floats(values["pose"], "pose") if values.get("pose") else None
    axis_pose = _floats(values["axis_pose"], "axis_pose") if values.get("axis_pose") else None
    axis_ends = (
        _floats(values["axis_ends"], "axis_ends").reshape(2, 2) if values.get("axis_ends") else None
    )
    return NodeStatus(
        status=status,
        request=request,
        stamp=float(values.get("stamp", "nan")),
        pose=pose,
        candidates=cands,
        reason=values.get("reason", ""),
        values=values,
        axis_pose=axis_pose,
        axis_ends=axis_ends,
    )
