"""``symloc bench localization``: many worlds, each mapped anew, many trials, symloc and AMCL.

A sweep is a list of :class:`WorldTask` s. Each task builds its world, maps it with its own
seed (laser SLAM over a mapping trip and the visual map of its symmetric place:
:func:`symloc.bench.scenario.build_scenario`), then runs its trials
(:func:`symloc.bench.trial.run_trial`, both methods on the same start). Tasks run in parallel
through :func:`symloc.bench.sweep.run_sweep`; a task's result depends only on the task, so the
sweep's JSON is the same for any worker count.

:func:`summarize` folds the trials into rows per (family, method) with Wilson 95 % intervals of
each rate, median time and distance to the first claim, the 95th percentile of the tracking
error and the coverage of the published covariance; and the heading's grade (corridors: status
``axis``, :mod:`symloc.bench.grading`): the share of trials whose first heading output was
right (``heading_correct``), the share with any heading output off by more than the tolerance
(``heading_wrong``), the median time to the first heading, the trials with an axis estimate and
how often the axis estimates' 95 % ellipsoids covered the truth.
"""

from __future__ import annotations

import math
import tempfile
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from symloc.localizer.config import LocalizerConfig
from symloc.sim.rooms import Room
from symloc.vision.verification import VerificationSettings

from .grading import GRADES
from .scenario import Scenario, build_scenario
from .stats import wilson_interval
from .trial import (
    DEFAULT_METHODS,
    METHODS,
    TrialConfig,
    TrialResult,
    TrialSpec,
    needs_keyframes,
    run_trial,
)
from .world_sources import WorldRef, build_world, world_spec

__all__ = [
    "MAPPING_REACH",
    "WorldResult",
    "WorldTask",
    "bench_scenario",
    "run_world",
    "summarize",
    "trial_rows",
]


#: A mapping trip's reach [m] that leaves keyframes within the camera's check of every place
#: the robot can go, facing every way (:attr:`WorldTask.mapping_reach`): the keyframes' own
#: (:attr:`symloc.vision.verification.VerificationSettings.max_distance`). The bench's
#: default: on the dev split it cut the median time to the first claim from 2.9 to 1.9 s
#: (210 correct against 209, never wrong) once the claim gate withheld claims over walls the
#: map never observed (:attr:`symloc.localizer.claim.ClaimConfig.max_unmapped_share`); before,
#: the camera decided in a cross's arm the lap never entered, and one claim was published
#: 12 cm off.
MAPPING_REACH: float = VerificationSettings().max_distance


@dataclass(frozen=True)
class WorldTask:
    """One world of a sweep: how to build it and its trials.

    The world's robot and mapping run are seeded by ``ref.robot_seed``, trial ``i`` by
    ``ref.trial_seed(i)`` (:class:`~symloc.bench.world_sources.WorldRef`: independent of the
    other worlds and trials and of the worker that runs it). ``mapping_reach`` [m]: on SLAM maps, after
    its lap along the walls the mapping robot stops and looks around until no place it can
    reach is farther than this from its trip (``build_scenario``'s ``explore_stops``; 0: the
    lap only; the default :data:`MAPPING_REACH` covers every place with keyframes).
    """

    ref: WorldRef
    trials: int
    kinds: tuple[str, ...] = ("global", "kidnap")
    regime: str = "ideal"
    map_source: str = "slam"
    config: TrialConfig = field(default_factory=TrialConfig)
    methods: tuple[str, ...] = DEFAULT_METHODS
    mapping_reach: float = MAPPING_REACH


@dataclass(frozen=True)
class WorldResult:
    """A task's outcome: the world's truth, the mapping notes, the trials, costs [s], and the
    world's metadata (:attr:`symloc.sim.world_file.WorldSpec.metadata`: e.g. a furnished
    room's base order and near-symmetry overlap)."""

    world_id: str
    family: str
    order: int
    symmetric: bool
    mapped_place: bool
    notes: tuple[str, ...]
    trials: tuple[TrialResult, ...]
    map_seconds: float
    trial_seconds: float
    error: str = ""
    metadata: dict[str, Any] = field(default_factory=dict)


def bench_scenario(
    ref: WorldRef,
    room: Room,
    workdir: Path,
    *,
    regime: str,
    map_source: str = "slam",
    mapping_reach: float = MAPPING_REACH,
    keyframes: bool = True,
) -> Scenario:
    """Map ``room`` (the world ``ref`` names) as the bench does: its own robot
    (:attr:`WorldRef.robot_seed`), one lap along the walls, then stops to look around until no
    reachable place is farther than ``mapping_reach`` [m] from the trip, with keyframes
    (SLAM maps only) when ``keyframes``. Benchmarks that study the bench's maps build them here."""
    return build_scenario(
        room,
        rng=ref.robot_seed,
        workdir=workdir,
        map_source=map_source,
        explore_laps=1.0,
        explore_stops=mapping_reach,
        regime=regime,
        keyframes=True if keyframes and map_source == "slam" else None,
    )


def run_world(task: WorldTask) -> WorldResult:
    """Build, map and run one world (the function each worker runs)."""
    t0 = time.perf_counter()
    world = world_spec(task.ref)
    room: Room = world.build() if world is not None else build_world(task.ref)
    order = int(room.order)
    with tempfile.TemporaryDirectory(prefix="symloc-bench-") as tmp:
        scen = bench_scenario(
            task.ref,
            room,
            Path(tmp),
            regime=task.regime,
            map_source=task.map_source,
            mapping_reach=task.mapping_reach,
            # deciding where the robot stands verifies against keyframes of the mapping trip;
            # recording them draws from their own stream, so the map and the other methods'
            # trials are the same with and without them
            keyframes=needs_keyframes(task.methods, LocalizerConfig().decide_here),
        )
        t1 = time.perf_counter()
        trials = []
        try:
            for i in range(task.trials):
                spec = TrialSpec(
                    world_id=task.ref.world_id,
                    family=task.ref.family,
                    index=i,
                    kind=task.kinds[i % len(task.kinds)],
                    seed=task.ref.trial_seed(i),
                )
                trials.append(run_trial(scen, spec, task.config, methods=task.methods))
        finally:
            scen.close()
    return WorldResult(
        world_id=task.ref.world_id,
        family=task.ref.family,
        order=order,
        symmetric=order != 1,
        mapped_place=scen.mapped is not None,
        notes=tuple(scen.notes),
        trials=tuple(trials),
        map_seconds=t1 - t0,
        trial_seconds=time.perf_counter() - t1,
        metadata={} if world is None else world.meta,
    )


def trial_rows(results: Sequence[WorldResult]) -> list[dict[str, Any]]:
    """One flat dict per (trial, method), for JSON and for :func:`summarize`."""
    rows = []
    for w in results:
        for tr in w.trials:
            for method, mr in tr.results.items():
                row: dict[str, Any] = {
                    "world": w.world_id,
                    "family": w.family,
                    "order": w.order,
                    "trial": tr.spec.index,
                    "kind": tr.spec.kind,
                    "seed": tr.spec.seed,
                    "method": method,
                    "start": list(tr.start),
                    "kidnap_to": None if tr.kidnap_to is None else list(tr.kidnap_to),
                    "final_status": mr.final_status,
                    "final_reason": mr.final_reason,
                    "collisions": mr.collisions,
                    "sim_time_s": mr.sim_time,
                    # the localizer's last notes: why a trial ended as it did
                    "steps": list(mr.steps),
                }
                row.update(mr.grade.as_dict())
                rows.append(row)
    return rows


def _median(values: list[float]) -> float:
    v = [x for x in values if math.isfinite(x)]
    return float(np.median(v)) if v else math.nan


def _pooled_coverage(rows: list[dict[str, Any]]) -> float:
    """Coverage over all claims: each trial's share weighted by its claims."""
    num = sum(r["coverage"] * r["claims"] for r in rows if math.isfinite(r["coverage"]))
    den = sum(r["claims"] for r in rows if math.isfinite(r["coverage"]))
    return num / den if den else math.nan


def summarize(rows: list[dict[str, Any]], by: str = "family") -> list[dict[str, Any]]:
    """Rows per (``by``, method) and an ``all`` row per method, with Wilson 95 % intervals."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((str(r[by]), r["method"]), []).append(r)
        groups.setdefault(("all", r["method"]), []).append(r)
    out = []
    keys = sorted(k for k in groups if k[0] != "all") + sorted(k for k in groups if k[0] == "all")
    for key in keys:
        group, method = key
        g = groups[key]
        n = len(g)
        row: dict[str, Any] = {by: group, "method": method, "trials": n}
        for grade in GRADES:
            k = sum(1 for r in g if r["grade"] == grade)
            lo, hi = wilson_interval(k, n)
            row[grade] = k
            row[f"{grade}_rate"] = k / n if n else math.nan
            row[f"{grade}_ci95"] = [lo, hi]
        claimed = [r for r in g if r["claims"] > 0]
        row["median_time_to_claim_s"] = _median([r["time_to_claim"] for r in claimed])
        row["median_distance_to_claim_m"] = _median([r["distance_to_claim"] for r in claimed])
        p95 = [r["error_p95"] for r in claimed if math.isfinite(r["error_p95"])]
        row["tracking_error_p95_m"] = float(np.percentile(p95, 50)) if p95 else math.nan
        hp95 = [r["heading_error_p95"] for r in claimed if math.isfinite(r["heading_error_p95"])]
        row["tracking_heading_error_p95_deg"] = (
            math.degrees(float(np.percentile(hp95, 50))) if hp95 else math.nan
        )
        row["covariance_coverage"] = _pooled_coverage(claimed)
        row["fraction_tracking"] = _median([r["fraction_tracking"] for r in g])
        row.update(_heading_summary(g))
        out.append(row)
    return out


def _heading_summary(g: list[dict[str, Any]]) -> dict[str, Any]:
    """The heading's columns of a summary row (rows without the heading's keys count as no
    heading output)."""
    n = len(g)
    row: dict[str, Any] = {}
    hits = {
        "heading_correct": sum(1 for r in g if r.get("first_heading_ok") is True),
        "heading_wrong": sum(1 for r in g if r.get("heading_wrong") is True),
    }
    for name, k in hits.items():
        lo, hi = wilson_interval(k, n)
        row[name] = k
        row[f"{name}_rate"] = k / n if n else math.nan
        row[f"{name}_ci95"] = [lo, hi]
    row["median_time_to_heading_s"] = _median([r.get("time_to_heading", math.nan) for r in g])
    axis = [r for r in g if r.get("axis_estimates", 0) > 0]
    row["axis_trials"] = len(axis)
    covered = [r.get("first_axis_covered") for r in axis]
    known = [c for c in covered if c is not None]
    row["axis_first_covered_rate"] = (
        sum(1 for c in known if c is True) / len(known) if known else math.nan
    )
    num = sum(r["axis_coverage"] * r["axis_estimates"] for r in axis)
    den = sum(r["axis_estimates"] for r in axis)
    row["axis_coverage"] = num / den if den else math.nan
    return row


def method_order(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """``rows`` in :data:`METHODS` order inside each group (for printing)."""
    rank = {m: i for i, m in enumerate(METHODS)}
    return sorted(
        rows, key=lambda r: (r.get("family", "") == "all", r.get("family", ""), rank[r["method"]])
    )


def world_summary(w: WorldResult) -> dict[str, Any]:
    """What a world's JSON entry records besides its trials."""
    d = asdict(w)
    d.pop("trials")
    d["notes"] = list(w.notes)
    return d
