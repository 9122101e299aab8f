"""The SLAM benchmark: symloc and its peers on the same CARMEN input, per (log, seed).

One task (:class:`SlamBenchTask`) is one log with one seed under one odometry choice:

1. the odometry is made once (:func:`~symloc.bench.slam_runs.carmen_odometry`: the regime
   applied to the corrected increments with the seed ``SeedSequence([seed, crc32(log name)])``,
   or the log's own odometry);
2. symloc runs in its own process (:mod:`symloc.bench.slam_child`, default
   :class:`~symloc.slam.SlamParams`, the same for every log), measured by
   :func:`~symloc.bench.measure.run_measured` (peak RSS, CPU time);
3. each peer runs on a CARMEN log holding the same ranges and the same odometry in both pose
   fields (:func:`~symloc.bench.peers.write_peer_log`), measured the same way;
4. every trajectory is scored against the corrected poses (ATE RMSE and maximum error after
   SE(2) alignment, :func:`~symloc.bench.slam_metrics.ate`).

:func:`summarize` aggregates the rows per log and system and checks issue 21's targets
(:data:`TARGETS`). The real-time factor is the log's duration over the process's CPU time
(reading the log and starting Python included), and only where the log's stamps are usable.
"""

from __future__ import annotations

import math
import sys
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from symloc.bench.measure import run_measured
from symloc.bench.peers.gmapping import GMappingPeer, PeerUnavailableError, write_peer_log
from symloc.bench.slam_metrics import ate
from symloc.bench.slam_runs import carmen_odometry, log_duration, log_name, odometry_seed
from symloc.errors import ConfigurationError
from symloc.files.atomic import atomic_path
from symloc.io.carmen import CarmenLog, read_carmen

__all__ = [
    "TARGETS",
    "SlamBenchTask",
    "log_name",
    "odometry_seed",
    "run_bench_task",
    "summarize",
]

#: Issue 21's targets per odometry choice: ATE RMSE per pair [m] (or "at most the best peer"),
#: maximum error per pair [m], median ATE over pairs [m]; memory [MiB] and real-time factor
#: apply to every choice.
TARGETS: dict[str, dict[str, float | bool]] = {
    "realistic": {"pair_ate": 0.05, "pair_or_best_peer": True, "median_ate": 0.05},
    "log": {"pair_ate": 0.05, "pair_or_best_peer": True, "median_ate": 0.05},
    "heavy": {"pair_ate": 0.20, "pair_max": 0.60, "median_ate": 0.10},
}
PEAK_MB = 300.0
MIN_REALTIME = 10.0


@dataclass(frozen=True)
class SlamBenchTask:
    """One (log, seed) run of the benchmark.

    Attributes
    ----------
    log : str
        CARMEN log path.
    seed : int
    odometry : str
        ``realistic``, ``heavy`` or ``log``.
    peers : tuple of (name, binary path)
        Built peers to run beside symloc.
    max_scans : int, optional
        Only the first scans (tests).
    timeout : float, optional
        Per process [s].
    """

    log: str
    seed: int
    odometry: str
    peers: tuple[tuple[str, str], ...] = ()
    max_scans: int | None = None
    timeout: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)


def _read(task: SlamBenchTask) -> CarmenLog:
    log = read_carmen(task.log)
    if task.max_scans is None:
        return log
    return CarmenLog(log.scans[: task.max_scans], log.odometry, log.params, log.skipped)


def _scores(reference: np.ndarray, poses: np.ndarray) -> dict[str, float]:
    a = ate(reference, poses)
    return {"ate_rmse_m": a.rmse, "ate_mean_m": a.mean, "ate_max_m": a.max}


def run_bench_task(task: SlamBenchTask) -> dict[str, Any]:
    """Run symloc and the peers on one (log, seed); a JSON-ready row (see module docstring)."""
    name = log_name(task.log)
    log = _read(task)
    reference = log.laser_poses
    duration = log_duration(log.stamps)
    row: dict[str, Any] = {
        "log": name,
        "seed": int(task.seed),
        "odometry": task.odometry,
        "scans": len(log.scans),
        "duration_s": duration,
        "systems": {},
    }
    try:
        rng = np.random.default_rng(odometry_seed(name, task.seed))
        odom = carmen_odometry(log, task.odometry, rng, name=name)
    except ConfigurationError as err:
        row["skipped"] = str(err)
        return row
    row["odometry_ate_rmse_m"] = ate(reference, odom).rmse
    systems: dict[str, dict[str, Any]] = row["systems"]
    with tempfile.TemporaryDirectory(prefix="symloc-slam-bench-") as tmp:
        odo_path = Path(tmp) / "odometry.npy"
        out_path = Path(tmp) / "symloc.npz"
        with atomic_path(odo_path) as tmp_npy:
            np.save(tmp_npy, odom)
        cmd = [sys.executable, "-m", "symloc.bench.slam_child"]
        cmd += ["--log", task.log, "--odometry", str(odo_path), "--out", str(out_path)]
        if task.max_scans is not None:
            cmd += ["--max-scans", str(task.max_scans)]
        m = run_measured(cmd, timeout=task.timeout)
        entry: dict[str, Any] = {
            "peak_rss_mb": m.peak_rss_mb,
            "cpu_s": m.cpu_s,
            "wall_s": m.wall_s,
            "realtime_factor_cpu": duration / m.cpu_s if duration and m.cpu_s > 0 else None,
        }
        if m.returncode == 0 and out_path.is_file():
            with np.load(out_path) as data:
                poses = data["poses"]
                summary = json_loads(str(data["summary"]))
            entry.update(_scores(reference, poses))
            entry.update(
                {
                    k: summary[k]
                    for k in (
                        "loops_accepted",
                        "loops_rejected",
                        "loops_rejected_by_reason",
                        "degenerate_fraction",
                        "odometry_model",
                        "doubtful",
                        "warnings",
                    )
                    if k in summary
                }
            )
            entry["slam_cpu_s"] = summary.get("slam_cpu_s")
        else:
            tail = "\n".join(m.stderr.strip().splitlines()[-5:])
            entry["error"] = ("timed out" if m.timed_out else f"exit {m.returncode}") + f": {tail}"
        systems["symloc"] = entry
        if task.peers:
            peer_log = write_peer_log(Path(tmp) / "peer.log", [s.scan for s in log.scans], odom)
            first = log.scans[0].scan
            for peer_name, binary in task.peers:
                pe: dict[str, Any] = {}
                try:
                    run = GMappingPeer(Path(binary), peer_name).run(
                        peer_log,
                        n_scans=len(log.scans),
                        angle_min=first.angle_min,
                        angle_increment=first.angle_increment,
                        seed=task.seed,
                        timeout=task.timeout,
                    )
                except PeerUnavailableError as err:
                    pe["error"] = str(err)
                else:
                    pe.update(_scores(reference, run.poses))
                    pe["peak_rss_mb"] = run.measured.peak_rss_mb
                    pe["cpu_s"] = run.measured.cpu_s
                    pe["wall_s"] = run.measured.wall_s
                    pe["realtime_factor_cpu"] = (
                        duration / run.measured.cpu_s
                        if duration and run.measured.cpu_s > 0
                        else None
                    )
                    pe["scans_processed"] = int(run.processed.sum())
                systems[peer_name] = pe
    return row


def json_loads(text: str) -> dict[str, Any]:
    """Parse the child's JSON summary."""
    import json

    out = json.loads(text)
    if not isinstance(out, dict):
        raise ConfigurationError("slam child: expected a JSON object summary")
    return out


def _finite(values: Sequence[Any]) -> list[float]:
    return [float(v) for v in values if v is not None and math.isfinite(float(v))]


def summarize(rows: Sequence[Mapping[str, Any]], odometry: str) -> dict[str, Any]:
    """Per-log aggregates per system and issue 21's target checks.

    Returns ``{"logs": {log: {system: {...}}}, "targets": {...}, "pairs": [...]}`` where each
    system holds ``ate_mean_m`` (mean over seeds of the ATE RMSE), ``ate_worst_m`` (largest
    ATE RMSE), ``max_error_m`` (largest single-pose error), ``peak_rss_mb`` (largest),
    ``realtime_factor_cpu`` (smallest), loop closures (mean) and the number of runs and errors.
    """
    logs: dict[str, dict[str, dict[str, Any]]] = {}
    pairs: list[dict[str, Any]] = []
    for r in rows:
        if "skipped" in r:
            logs.setdefault(r["log"], {})
            continue
        for sys_name, e in r["systems"].items():
            logs.setdefault(r["log"], {}).setdefault(sys_name, {"runs": []})["runs"].append(e)
        sl = r["systems"].get("symloc", {})
        peers = {
            k: v["ate_rmse_m"]
            for k, v in r["systems"].items()
            if k != "symloc" and v.get("ate_rmse_m") is not None
        }
        pairs.append(
            {
                "log": r["log"],
                "seed": r["seed"],
                "symloc_ate_m": sl.get("ate_rmse_m"),
                "symloc_max_m": sl.get("ate_max_m"),
                "best_peer_ate_m": min(peers.values()) if peers else None,
                "doubtful": sl.get("doubtful"),
            }
        )
    out_logs: dict[str, dict[str, Any]] = {}
    for lg, systems in logs.items():
        out_logs[lg] = {}
        for sys_name, agg in systems.items():
            runs = agg["runs"]
            ates = _finite([e.get("ate_rmse_m") for e in runs])
            out_logs[lg][sys_name] = {
                "runs": len(runs),
                "errors": sum(1 for e in runs if "error" in e),
                "ate_mean_m": float(np.mean(ates)) if ates else None,
                "ate_worst_m": max(ates) if ates else None,
                "max_error_m": max(_finite([e.get("ate_max_m") for e in runs]), default=None),
                "peak_rss_mb": max(_finite([e.get("peak_rss_mb") for e in runs]), default=None),
                "realtime_factor_cpu": min(
                    _finite([e.get("realtime_factor_cpu") for e in runs]), default=None
                ),
                "loops_accepted": _mean(_finite([e.get("loops_accepted") for e in runs])),
                "loops_rejected": _mean(_finite([e.get("loops_rejected") for e in runs])),
                "doubtful_runs": sum(1 for e in runs if e.get("doubtful")),
            }
    return {"logs": out_logs, "pairs": pairs, "targets": check_targets(rows, pairs, odometry)}


def _mean(v: list[float]) -> float | None:
    return float(np.mean(v)) if v else None


def check_targets(
    rows: Sequence[Mapping[str, Any]], pairs: Sequence[Mapping[str, Any]], odometry: str
) -> dict[str, Any]:
    """Issue 21's pass/fail checks for symloc (see :data:`TARGETS`)."""
    t = TARGETS.get(odometry, TARGETS["realistic"])
    ran = [p for p in pairs if p["symloc_ate_m"] is not None]
    failed_pairs = []
    for p in pairs:
        a, mx, best = p["symloc_ate_m"], p["symloc_max_m"], p["best_peer_ate_m"]
        if a is None:
            failed_pairs.append(f"{p['log']}/{p['seed']}: no result")
            continue
        ok = a < float(t["pair_ate"])
        if t.get("pair_or_best_peer") and best is not None:
            ok = ok or a <= best
        if "pair_max" in t and mx is not None:
            ok = ok and mx < float(t["pair_max"])
        if not ok:
            failed_pairs.append(f"{p['log']}/{p['seed']}")
    med = float(np.median([p["symloc_ate_m"] for p in ran])) if ran else None
    peaks = [
        (r["log"], r["systems"]["symloc"].get("peak_rss_mb"))
        for r in rows
        if "symloc" in r.get("systems", {})
    ]
    over_mem = sorted({lg for lg, mb in peaks if mb is None or not mb < PEAK_MB})
    slow = sorted(
        {
            r["log"]
            for r in rows
            if "symloc" in r.get("systems", {})
            and r.get("duration_s")
            and not (r["systems"]["symloc"].get("realtime_factor_cpu") or 0) >= MIN_REALTIME
        }
    )
    return {
        "pairs": len(pairs),
        "pairs_failed": failed_pairs,
        "pair_rule": (
            f"ATE < {t['pair_ate']} m"
            + (" or <= the best peer's" if t.get("pair_or_best_peer") else "")
            + (f", max error < {t['pair_max']} m" if "pair_max" in t else "")
        ),
        "median_ate_m": med,
        "median_target_m": float(t["median_ate"]),
        "median_ok": med is not None and med < float(t["median_ate"]),
        "memory_limit_mb": PEAK_MB,
        "logs_over_memory": over_mem,
        "min_realtime": MIN_REALTIME,
        "logs_below_realtime": slow,
        "all_ok": not failed_pairs
        and med is not None
        and med < float(t["median_ate"])
        and not over_mem
        and not slow,
    }
