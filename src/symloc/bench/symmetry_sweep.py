"""``symloc bench symmetry``: Algorithm 1 from random poses in many worlds, against the truth.

For each world (generated, from a file, or built in) the true rotational symmetry order of
what the lidar sees is computed from the geometry (:mod:`symloc.sim.symmetry_truth`); from
``poses`` random poses where the robot fits, one scan each (the regime's lidar) is judged by
:func:`symloc.symmetry.judge_symmetry`. Each judgement is

- ``correct``: symmetric with the true order (a circle's infinite order counts as the truth's
  0), or not symmetric in an asymmetric room;
- ``false_symmetric``: judged symmetric where the room is not, or with another order: the
  error that would make the localizer look for copies that do not exist;
- ``missed``: judged asymmetric in a symmetric room;
- ``unknown``: no verdict (too little of the room in range or in view).

The centre error of correct symmetric verdicts (judged centre against the true one) is kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from symloc.camera_model import DEFAULT_HFOV
from symloc.lidar_spec import PRESETS
from symloc.sim.camera import Camera
from symloc.symmetry import SymmetryConfig, SymmetryOrder, judge_symmetry

from .sensors import robot_hardware
from .stats import wilson_interval
from .world_sources import WorldRef, build_world

__all__ = ["OUTCOMES", "SymmetryTask", "run_symmetry_world", "summarize_symmetry"]

OUTCOMES = ("correct", "false_symmetric", "missed", "unknown")


@dataclass(frozen=True)
class SymmetryTask:
    """One world: how to build it, its seed, poses to judge from, lidar and regime."""

    ref: WorldRef
    seed: int
    poses: int
    lidar: str = "rplidar_a2"
    regime: str = "ideal"


def _order(order: SymmetryOrder) -> int:
    """An order as the truth writes it in the JSON (a circle is 0)."""
    return 0 if order.k is None else order.k


def run_symmetry_world(task: SymmetryTask) -> dict[str, Any]:
    """Judge ``task.poses`` scans in one world; plain values (picklable, JSON-ready)."""
    room = build_world(task.ref)
    preset = PRESETS[task.lidar]
    rng = np.random.default_rng(task.seed)
    hardware = robot_hardware(task.regime, preset, Camera(hfov=DEFAULT_HFOV), rng)
    session = hardware.session(rng, "query")
    truth = room.truth(glass_visible=task.regime == "ideal")
    config = SymmetryConfig.from_lidar(preset)
    rows = []
    for _ in range(task.poses):
        pose = room.sample_pose(rng)
        scan = session.scan(room.world, pose, (0.0, 0.0), 0.0)
        rep = judge_symmetry(scan, config=config)
        judged = rep.order if rep.symmetric and rep.order is not None else SymmetryOrder.finite(1)
        if rep.kind == "unknown" and not rep.symmetric:
            outcome = "unknown"
        elif rep.symmetric and judged == truth.symmetry_order:
            outcome = "correct"
        elif rep.symmetric:
            outcome = "false_symmetric"
        elif truth.order == 1:
            outcome = "correct"
        else:
            outcome = "missed"
        centre_error = math.nan
        if outcome == "correct" and rep.symmetric:
            c, s = math.cos(pose[2]), math.sin(pose[2])
            cx, cy = float(rep.center[0]), float(rep.center[1])
            world_c = np.array([pose[0] + c * cx - s * cy, pose[1] + s * cx + c * cy])
            centre_error = float(np.hypot(*(world_c - truth.center)))
        rows.append(
            {
                "kind": rep.kind,
                "judged_order": _order(judged),
                "outcome": outcome,
                "centre_error_m": centre_error,
            }
        )
    return {
        "world": task.ref.world_id,
        "family": task.ref.family,
        "true_order": int(truth.order),
        "judgements": rows,
    }


def summarize_symmetry(worlds: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rows per family and ``all``: counts and Wilson 95 % intervals of each outcome."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for w in worlds:
        for j in w["judgements"]:
            judgement = {**j, "symmetric_room": w["true_order"] != 1}
            groups.setdefault(w["family"], []).append(judgement)
            groups.setdefault("all", []).append(judgement)
    out = []
    for name in [*sorted(k for k in groups if k != "all"), "all"]:
        g = groups.get(name, [])
        n = len(g)
        row: dict[str, Any] = {"family": name, "judgements": n}
        for o in OUTCOMES:
            k = sum(1 for j in g if j["outcome"] == o)
            row[o] = k
            row[f"{o}_ci95"] = list(wilson_interval(k, n))
        errs = [j["centre_error_m"] for j in g if math.isfinite(j["centre_error_m"])]
        row["centre_error_p95_m"] = float(np.percentile(errs, 95)) if errs else math.nan
        row["symmetric_rooms_share"] = (
            sum(1 for j in g if j["symmetric_room"]) / n if n else math.nan
        )
        out.append(row)
    return out
