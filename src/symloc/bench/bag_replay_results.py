"""The results file of ``benchmarks/bench_bag_replay.py`` (issue 28: bag replay on real logs).

The benchmark runs each CARMEN log through the command line (``carmen-to-bag``, ``map build``,
``replay``, ``experiment amcl-carmen``) and keeps one row per log (its
``bench_bag_replay.partial.jsonl``). :func:`summary_row` reduces such a row to the figures the
README quotes: the replay's mean error on the experiment's map and odometry, the experiment's,
their difference, the scans replay dropped (count, share and reasons), the replay as a user runs
it (the log's own odometry on the map of ``map build --carmen``) and the ``--build-map`` ATEs.
:func:`write_bag_replay_results` writes them with their provenance
(:mod:`symloc.bench.results_file`); README.md renders them from
``docs/results/bench_bag_replay.json`` (:mod:`symloc.readme`).
"""

from __future__ import annotations

import ast
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from symloc.bench.provenance import RunClock

__all__ = [
    "TARGETS",
    "replay_counts",
    "summary_row",
    "within_targets",
    "write_bag_replay_results",
]

TARGETS: dict[str, float] = {"difference_m": 0.02, "dropped_share_below": 0.01}
"""Issue 28's targets: replay's mean error within 0.02 m of the experiment's on the same log,
map and odometry, and fewer than 1 % of the scans dropped."""


def replay_counts(text: str) -> dict[str, Any] | None:
    """The scans ``symloc replay`` used and dropped, from its standard output (``scans used: 906
    of 910`` and ``dropped: {'reason': n, ...}``): ``{"used", "scans", "dropped",
    "dropped_share", "reasons"}``, or None when the output has no ``scans used`` line."""
    used = re.search(r"scans used: (\d+) of (\d+)", text)
    if used is None:
        return None
    n_used, n_scans = int(used.group(1)), int(used.group(2))
    reasons: dict[str, int] = {}
    line = re.search(r"^dropped: (\{.*\})\s*$", text, re.MULTILINE)
    if line is not None:
        try:
            parsed = ast.literal_eval(line.group(1))
        except (ValueError, SyntaxError):
            parsed = {}
        if isinstance(parsed, dict):
            reasons = {str(k): int(v) for k, v in parsed.items()}
    return {
        "used": n_used,
        "scans": n_scans,
        "dropped": n_scans - n_used,
        "dropped_share": (n_scans - n_used) / n_scans if n_scans else None,
        "reasons": reasons,
    }


def _num(value: Any) -> float | None:
    """``value`` as a float, None for a missing or non-finite one."""
    if value is None:
        return None
    v = float(value)
    return v if math.isfinite(v) else None


def within_targets(row: Mapping[str, Any]) -> bool:
    """Whether a :func:`summary_row` meets :data:`TARGETS` (a missing figure does not)."""
    diff = row.get("difference_m")
    share = row.get("dropped_share")
    return (
        diff is not None
        and abs(diff) <= TARGETS["difference_m"]
        and share is not None
        and share < TARGETS["dropped_share_below"]
    )


def summary_row(row: Mapping[str, Any]) -> dict[str, Any]:
    """The README's figures of one log from a ``bench_bag_replay.py`` row (its partial file's
    line): ``log``, ``seed``, ``scans``; on the experiment's map and odometry (step 6 against
    step 5) ``experiment_mean_m``, ``replay_mean_m``, ``difference_m``, ``replay_estimates``,
    ``dropped``, ``dropped_share``, ``dropped_reasons``, ``within_targets``; ``as_user`` (the
    log's own odometry on the map of ``map build --carmen``: dropped, mean error in the map
    frame and after a rigid fit, mean over the scans published as tracking); ``build_map``
    (``--build-map`` ATE against ``map build --carmen`` on the same odometry, and on the log's
    own); ``motion`` (the share of scan-to-scan motions whose first rotation exceeds 0.5 rad,
    the median step, and the share of AMCL's updates whose heading noise, drawn scan by scan, is
    over twice as wide as its model of the update's motion); ``amcl_variants`` (the
    experiment's AMCL again, as run and with one parameter changed: mean, median and largest
    error); ``wall_s``. Missing steps give None (an empty object for the last two)."""
    same = row.get("same_as_experiment") or {}
    counts = same.get("dropped") if isinstance(same.get("dropped"), Mapping) else None
    out: dict[str, Any] = {
        "log": row["log"],
        "seed": row.get("seed"),
        "scans": row.get("scans"),
        "experiment_mean_m": _num(same.get("amcl_carmen_mean")),
        "replay_mean_m": _num(same.get("replay_mean")),
        "difference_m": _num(same.get("difference")),
        "replay_estimates": same.get("replay_n"),
        "dropped": None if counts is None else counts["dropped"],
        "dropped_share": _num(same.get("dropped_share")),
        "dropped_reasons": {} if counts is None else dict(counts["reasons"]),
    }
    out["within_targets"] = within_targets(out) if same else None
    user_all = row.get("replay_all") or {}
    user_tracked = row.get("replay_tracked") or {}
    user_counts = row.get("dropped") if isinstance(row.get("dropped"), Mapping) else None
    out["as_user"] = {
        "dropped": None if user_counts is None else user_counts["dropped"],
        "dropped_share": _num(row.get("dropped_share")),
        "mean_m": _num(user_all.get("mean")),
        "mean_aligned_m": _num(user_all.get("mean_aligned")),
        "tracked_mean_m": _num(user_tracked.get("mean")),
        "tracked_estimates": user_tracked.get("n"),
    }
    mb = row.get("same_input_as_map_build") or {}
    out["build_map"] = {
        "map_build_ate_m": _num(mb.get("map_build_ate")),
        "build_map_ate_m": _num(mb.get("build_map_ate")),
        "difference_m": _num(mb.get("difference")),
        "own_odometry_ate_m": _num(row.get("build_map_ate")),
    }
    out["motion"] = {k: _num(v) for k, v in (row.get("motion") or {}).items()}
    out["amcl_variants"] = {
        k: {f: _num(x) for f, x in v.items()} for k, v in (same.get("amcl_variants") or {}).items()
    }
    out["wall_s"] = None if row.get("wall_s") is None else round(float(row["wall_s"]), 1)
    return out


def write_bag_replay_results(
    path: str | Path,
    rows: Sequence[Mapping[str, Any]],
    *,
    argv: Sequence[str],
    clock: RunClock,
    settings: Mapping[str, Any],
) -> Path:
    """Write the results file of a ``bench_bag_replay.py`` run: ``figures`` holds the
    :data:`TARGETS` and one :func:`summary_row` per row of ``rows`` (log by log, seed by
    seed), with the run's command (``python`` and ``argv``), commit, date, machine, load and
    wall time."""
    from symloc.bench.results_file import write_run_results

    return write_run_results(
        path,
        argv=argv,
        clock=clock,
        settings=settings,
        figures={"targets": dict(TARGETS), "rows": [summary_row(r) for r in rows]},
        program="python",
    )
