"""Kidnapped-robot trials per room: plain AMCL against symloc (the localization experiment)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from symloc._checks import as_rng

from .scenario import build_scenario, run_plain_amcl, run_symloc

__all__ = ["RoomTrials", "TrialRecord", "run_room_trials"]


@dataclass(frozen=True)
class TrialRecord:
    """One trial of one method: grade and cost (simulated s, m) until the final answer."""

    grade: str
    position_error: float
    heading_error: float
    time: float
    distance: float
    copy_index: int | None
    near_copy: int | None
    final_status: str
    reason: str


@dataclass
class RoomTrials:
    """All trials in one room for both methods."""

    room: str
    lab: str
    amcl: list[TrialRecord] = field(default_factory=list)
    symloc: list[TrialRecord] = field(default_factory=list)
    judge_errors: int = 0
    mapped: bool = True
    collisions: int = 0
    amcl_collisions: int = 0
    map_note: str = ""

    def rows(self) -> list[dict[str, Any]]:
        out = []
        for method, recs in (("amcl", self.amcl), ("symloc", self.symloc)):
            grades = [r.grade for r in recs]
            ok = [r for r in recs if r.grade == "correct"]
            out.append(
                {
                    "room": self.room,
                    "lab": self.lab,
                    "method": method,
                    "trials": len(recs),
                    "correct": grades.count("correct"),
                    "confident_wrong": grades.count("confident_wrong"),
                    "undetermined": grades.count("undetermined"),
                    "confident_wrong_symmetric_copy": sum(
                        1 for r in recs if r.grade == "confident_wrong" and r.copy_index
                    ),
                    "estimate_near_true_pose": sum(1 for r in recs if r.near_copy == 0),
                    "estimate_near_symmetric_copy": sum(1 for r in recs if r.near_copy),
                    "undetermined_estimate_on_wrong_copy": sum(
                        1 for r in recs if r.grade == "undetermined" and r.near_copy
                    ),
                    "median_time_s": float(np.median([r.time for r in ok])) if ok else math.nan,
                    "median_distance_m": float(np.median([r.distance for r in ok]))
                    if ok
                    else math.nan,
                    "reasons": _top_reasons(recs),
                    "collisions": self.collisions if method == "symloc" else self.amcl_collisions,
                }
            )
        return out


def _top_reasons(recs: list[TrialRecord], n: int = 3) -> dict[str, int]:
    counts: dict[str, int] = {}
    for r in recs:
        if r.grade != "correct":
            key = f"{r.grade}: {r.reason}"[:120]
            counts[key] = counts.get(key, 0) + 1
    return dict(sorted(counts.items(), key=lambda kv: -kv[1])[:n])


def run_room_trials(
    room: str,
    *,
    textured: bool = True,
    trials: int = 100,
    rng: np.random.Generator | int | None = None,
    workdir: Path | None = None,
    amcl_duration: float = 45.0,
    symloc_max_time: float = 150.0,
    progress: bool = True,
    preset: Any = None,
    map_source: str = "slam",
) -> RoomTrials:
    """Map ``room`` once, then kidnap the robot ``trials`` times; run both methods each time."""
    gen = as_rng(rng)
    scen = build_scenario(
        room, textured=textured, rng=gen, workdir=workdir, preset=preset, map_source=map_source
    )
    res = RoomTrials(room=room, lab="textured" if textured else "untextured")
    res.mapped = scen.mapped is not None
    res.map_note = "; ".join(scen.notes)
    iterator: Any = range(trials)
    if progress:
        from tqdm import tqdm

        iterator = tqdm(iterator, desc=f"{room} ({res.lab})", leave=False)
    localizer_judge_errors = 0
    try:
        for _ in iterator:
            start = scen.random_pose(gen)
            s = run_symloc(
                scen, start, np.random.default_rng(gen.integers(2**32)), max_time=symloc_max_time
            )
            fin = s.episode.final
            res.collisions += s.collisions
            localizer_judge_errors += int(getattr(s.localizer.judge, "errors", 0))
            res.symloc.append(
                TrialRecord(
                    grade=s.outcome.grade,
                    position_error=s.outcome.position_error,
                    heading_error=s.outcome.heading_error,
                    time=s.episode.time_to_final if fin.request is None else s.episode.time,
                    distance=s.episode.distance_to_final
                    if fin.request is None
                    else s.episode.distance,
                    copy_index=s.outcome.copy_index,
                    near_copy=s.outcome.near_copy,
                    final_status=fin.status.value,
                    reason=fin.reason,
                )
            )
            a = run_plain_amcl(
                scen, start, np.random.default_rng(gen.integers(2**32)), duration=amcl_duration
            )
            res.amcl_collisions += a.collisions
            res.amcl.append(
                TrialRecord(
                    grade=a.outcome.grade,
                    position_error=a.outcome.position_error,
                    heading_error=a.outcome.heading_error,
                    time=a.time,
                    distance=a.distance,
                    copy_index=a.outcome.copy_index,
                    near_copy=a.outcome.near_copy,
                    final_status="confident" if a.converged else "not confident",
                    reason=a.confidence_reason.split(":")[0],
                )
            )
    finally:
        # the mapping stage's judge and each trial's (built with the localizer)
        res.judge_errors = scen.judge.errors + localizer_judge_errors
        scen.close()
    return res
