"""The localizer's status and symmetric candidates as ROS messages.

**Status** (``diagnostic_msgs/DiagnosticArray`` on ``symloc/status``, one per scan, used or
not): one
``DiagnosticStatus`` named ``symloc: localization`` whose ``level`` is OK while tracking, WARN
while ambiguous / going to the centre / deciding / on a corridor's axis, ERROR when lost, and
whose ``message`` is ``"<status>: <reason>"``. Its ``values`` (key / value strings) are:

==================  ==========================================================================
key                 value
==================  ==========================================================================
``status``          tracking, ambiguous, going_to_centre, deciding, lost or axis
``reason``          one line saying why
``order``           symmetry order k when ambiguous ("" otherwise; 0 means a circle)
``pose``            "x y theta" [m m rad] in the map frame when tracking, else "" (also
                    while ``axis``: that pose is not earned)
``axis_pose``       status ``axis`` only: "x y theta" of the middle of the segment the robot
                    stands on, with the decided heading (map frame; also on
                    ``symloc/axis_pose`` with its covariance)
``axis_ends``       status ``axis`` only: "x0 y0 x1 y1" [m] the segment's ends
``axis_length``     status ``axis`` only: the segment's length [m]
``axis_std``        status ``axis`` only: "along across theta" stds [m m rad]
``axis_open_ends``  status ``axis`` only: ends lengthened into space the map does not cover
``candidates``      number of candidate poses
``candidate_<i>``   "x y theta weight" of candidate i (map frame)
``request``         go_to_centre, go_to, face_direction, capture_image, rotate or ""
``request_target``  "x y" [m] of a go_to_centre or go_to target in the robot (base) frame
``request_angle``   [rad] of a face_direction / rotate request (CCW positive)
``stamp``           the scan stamp [s] this status answers
``scan``            ``used``, or ``dropped`` when the localizer did not take this scan (then
                    the status is the last one, ``lost`` after a few unused scans in a row,
                    and ``reason`` says why)
``scans_used``      scans given to the localizer so far
``dropped``         messages dropped so far (all reasons)
``dropped/<why>``   messages dropped for that reason
``map_to_odom``     what the broadcast ``map -> odom`` is: sent with this scan (and the stamp it
                    carries), not updated since an earlier scan, or never sent
``recovered``       recoveries from a stuck state so far (clock jump, odometry reset, ...)
``recovered/<what>``  recoveries of that kind (:mod:`symloc.ros.core`)
==================  ==========================================================================

**Candidates** (``visualization_msgs/MarkerArray`` on ``symloc/candidates``): a DELETEALL
marker, then one ARROW per candidate pose (namespace ``symloc_candidates``, map frame, length
proportional to weight; status ``axis``: the segment's two ends), a LINE_STRIP along the
segment while ``axis`` (namespace ``symloc_axis``) and one TEXT_VIEW_FACING with the status,
for RViz.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from symloc.localizer import Estimate, Request, RequestKind, Status
from symloc.localizer.types import AxisPose
from symloc.msgs.header import header_fields
from symloc.msgs.pose import pose_fields
from symloc.symmetry.order import SymmetryOrder

__all__ = ["LEVELS", "candidates_to_fields", "status_to_fields"]

LEVELS = {
    Status.TRACKING: 0,
    Status.AMBIGUOUS: 1,
    Status.GOING_TO_CENTRE: 1,
    Status.DECIDING: 1,
    Status.LOST: 2,
    Status.AXIS: 1,
}

_ARROW, _LINE_STRIP, _TEXT, _DELETEALL = 0, 4, 9, 3


def _order_text(order: SymmetryOrder | None) -> str:
    """`` (order k)`` for people; a circle reads ``inf``."""
    return "" if order is None else f" (order {order})"


def _order_value(order: SymmetryOrder | None) -> str:
    """The ``order`` diagnostic value: k, ``0`` for a circle (the field's documented form),
    ``""`` when not ambiguous."""
    if order is None:
        return ""
    return "0" if order.k is None else str(order.k)


def _fmt(values: Any) -> str:
    return " ".join(f"{float(v):.6g}" for v in np.asarray(values, dtype=np.float64).reshape(-1))


def _axis_values(axis: AxisPose | None) -> list[tuple[str, str]]:
    """The ``axis_*`` values of status ``axis`` (none otherwise)."""
    if axis is None:
        return []
    frame = axis.ends[1] - axis.ends[0]
    length = float(np.hypot(*frame))
    unit = frame / length if length > 0 else np.array([1.0, 0.0])
    normal = np.array([-unit[1], unit[0]])
    cxy = axis.covariance[:2, :2]
    stds = [
        float(np.sqrt(max(unit @ cxy @ unit, 0.0))),
        float(np.sqrt(max(normal @ cxy @ normal, 0.0))),
        float(np.sqrt(max(axis.covariance[2, 2], 0.0))),
    ]
    return [
        ("axis_pose", _fmt(axis.pose)),
        ("axis_ends", _fmt(axis.ends)),
        ("axis_length", f"{length:.6g}"),
        ("axis_std", _fmt(stds)),
        ("axis_open_ends", str(axis.open_ends)),
    ]


def _request_values(req: Request | None) -> list[tuple[str, str]]:
    if req is None:
        return [("request", "")]
    out = [("request", req.kind.value)]
    if req.kind in (RequestKind.GO_TO_CENTRE, RequestKind.GO_TO) and req.target is not None:
        out.append(("request_target", _fmt(req.target)))
    if req.angle is not None:
        out.append(("request_angle", f"{req.angle:.6g}"))
    return out


def status_to_fields(
    est: Estimate,
    *,
    stamp: float,
    frame_id: str,
    scans_used: int,
    dropped: Mapping[str, int],
    recovered: Mapping[str, int] | None = None,
    scan_used: bool = True,
) -> dict[str, Any]:
    """A diagnostic_msgs/DiagnosticArray field dict describing ``est`` (see module doc)."""
    values: list[tuple[str, str]] = [
        ("status", est.status.value),
        ("reason", est.reason),
        ("order", _order_value(est.order)),
        ("pose", "" if est.pose is None else _fmt(est.pose)),
        ("candidates", str(len(est.hypotheses))),
    ]
    values += [(f"candidate_{i}", _fmt([*h.pose, h.weight])) for i, h in enumerate(est.hypotheses)]
    values += _axis_values(est.axis)
    values += _request_values(est.request)
    values += [
        ("stamp", f"{stamp:.9f}"),
        ("scan", "used" if scan_used else "dropped"),
        ("scans_used", str(scans_used)),
        ("dropped", str(sum(dropped.values()))),
    ]
    values += [(f"dropped/{k}", str(v)) for k, v in sorted(dropped.items())]
    rec = recovered or {}
    values += [("recovered", str(sum(rec.values())))]
    values += [(f"recovered/{k}", str(v)) for k, v in sorted(rec.items())]
    return {
        "header": header_fields(stamp, frame_id),
        "status": [
            {
                "level": LEVELS[est.status],
                "name": "symloc: localization",
                "message": f"{est.status.value}: {est.reason}",
                "hardware_id": "symloc",
                "values": [{"key": k, "value": v} for k, v in values],
            }
        ],
    }


def axis_ends(est: Estimate) -> list[Any]:
    """The axis segment's two end points (2,) of status ``axis`` (none otherwise)."""
    return [] if est.axis is None else list(est.axis.ends)


def candidates_to_fields(est: Estimate, *, stamp: float, frame_id: str) -> dict[str, Any]:
    """A visualization_msgs/MarkerArray field dict of the candidate poses (see module doc)."""
    header = header_fields(stamp, frame_id)
    markers: list[dict[str, Any]] = [{"header": header, "action": _DELETEALL}]
    colour = {
        Status.TRACKING: (0.1, 0.8, 0.1),
        Status.LOST: (0.8, 0.1, 0.1),
    }.get(est.status, (1.0, 0.6, 0.0))
    for i, h in enumerate(est.hypotheses):
        markers.append(
            {
                "header": header,
                "ns": "symloc_candidates",
                "id": i,
                "type": _ARROW,
                "action": 0,
                "pose": pose_fields(h.pose),
                "scale": {"x": 0.2 + 0.6 * float(h.weight), "y": 0.05, "z": 0.05},
                "color": {"r": colour[0], "g": colour[1], "b": colour[2], "a": 1.0},
            }
        )
    if est.axis is not None:
        markers.append(
            {
                "header": header,
                "ns": "symloc_axis",
                "id": 0,
                "type": _LINE_STRIP,
                "action": 0,
                "pose": pose_fields([0.0, 0.0, 0.0]),
                "scale": {"x": 0.05, "y": 0.0, "z": 0.0},
                "color": {"r": colour[0], "g": colour[1], "b": colour[2], "a": 1.0},
                "points": [{"x": float(e[0]), "y": float(e[1]), "z": 0.0} for e in axis_ends(est)],
            }
        )
    if est.hypotheses:
        centre = np.mean([h.pose[:2] for h in est.hypotheses], axis=0)
        markers.append(
            {
                "header": header,
                "ns": "symloc_status",
                "id": 0,
                "type": _TEXT,
                "action": 0,
                "pose": pose_fields([centre[0], centre[1], 0.0]),
                "scale": {"x": 0.0, "y": 0.0, "z": 0.25},
                "color": {"r": 1.0, "g": 1.0, "b": 1.0, "a": 1.0},
                "text": est.status.value + _order_text(est.order),
            }
        )
    return {"markers": markers}
