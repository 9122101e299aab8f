"""``symloc bench slam``: symloc's SLAM beside its peers on the CARMEN logs, per (log, seed).

Every (log, seed) is one task of :func:`symloc.bench.sweep.run_sweep`
(:func:`symloc.bench.slam_bench.run_bench_task`): the same odometry for every system, each
system in its own measured process. Prints a table per log (ATE RMSE mean and worst over the
seeds and the largest single-pose error, for each system; peak memory; real-time factor
(CPU) where the log has usable stamps; loop closures accepted / rejected; runs flagged
doubtful), then issue 21's targets, and writes JSON and a PNG into ``--out``.
"""

from __future__ import annotations

import argparse
import datetime
import os
import sys
from pathlib import Path
from typing import Any

from symloc.cli import options
from symloc.cli.bench_commands._common import add_sweep_arguments, write_json

__all__ = ["register"]

PEERS = ("gmapping",)


def register(subparsers: Any) -> None:
    """Add ``slam`` to ``symloc bench``."""
    from symloc.bench.slam_runs import ODOMETRY_CHOICES

    p: argparse.ArgumentParser = subparsers.add_parser(
        "slam",
        help="SLAM on the CARMEN logs beside GMapping: ATE, memory, speed, loop closures",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--carmen",
        type=Path,
        default=None,
        metavar="DIR",
        help="folder of CARMEN logs (*.log / *.log.gz; default ../shared/data/carmen or "
        "$SYMLOC_SHARED_DATA/carmen), or one log file",
    )
    p.add_argument("--logs", nargs="*", default=None, help="only these logs (names, e.g. intel)")
    p.add_argument(
        "--seeds",
        type=options.nonnegative_int,
        nargs="+",
        default=[0],
        help="odometry-noise seeds (default 0)",
    )
    p.add_argument(
        "--odometry",
        choices=ODOMETRY_CHOICES,
        default="realistic",
        help="realistic: calibrated wheels (1.5 %% / 1 %% bias + small noise); heavy: "
        "GMapping's filter noise as the truth; log: the log's own odometry",
    )
    p.add_argument("--peers", nargs="*", choices=PEERS, default=[], help="peers to run beside")
    p.add_argument(
        "--peer-src",
        type=Path,
        default=None,
        metavar="PATH",
        help="openslam_gmapping source checkout to build the peer from (without it the peer "
        "is skipped)",
    )
    p.add_argument(
        "--peer-build",
        type=options.output_folder,
        default=None,
        metavar="DIR",
        help="build folder of the peer (default ~/.cache/symloc/peers/...)",
    )
    p.add_argument(
        "--max-scans", type=options.positive_int, default=None, help="only the first N scans"
    )
    p.add_argument("--timeout", type=options.positive_float, default=3600.0, help="per process [s]")
    add_sweep_arguments(p, "bench slam")
    options.add_results(p, "docs/results/bench_slam_realistic.json")
    p.set_defaults(func=run)


def _logs(args: argparse.Namespace) -> list[Path]:
    """The logs to run, checked before any work: a ConfigurationError when none is found or
    one named with ``--logs`` is missing."""
    from symloc.bench.shared_data import find_carmen_dir
    from symloc.bench.slam_runs import log_name
    from symloc.errors import ConfigurationError

    src = args.carmen if args.carmen is not None else find_carmen_dir()
    if src is None:
        raise ConfigurationError(
            "the CARMEN logs were not found: pass --carmen DIR (or set SYMLOC_SHARED_DATA)"
        )
    src = Path(src)
    if src.is_file():
        found = [src]
    elif src.is_dir():
        found = sorted(p for p in src.iterdir() if p.name.endswith((".log", ".log.gz")))
    else:
        raise ConfigurationError(f"--carmen {src}: not found; expected a CARMEN log or a folder")
    if args.logs:
        names = {log_name(p) for p in found}
        missing = [n for n in dict.fromkeys(args.logs) if n not in names]
        if missing:
            raise ConfigurationError(
                f"--logs: not found in {src}: {', '.join(missing)}"
                f" (found: {', '.join(sorted(names)) or 'none'})"
            )
        found = [p for p in found if log_name(p) in set(args.logs)]
    if not found:
        raise ConfigurationError(f"--carmen {src}: no *.log or *.log.gz file there")
    return found


def _fmt(v: Any, spec: str = ".3f") -> str:
    return "-" if v is None else format(v, spec)


def run(args: argparse.Namespace) -> int:
    """Build the peers, run the sweep, print the table and the targets, write JSON + PNG."""
    from symloc.bench.peers import GMappingPeer, PeerUnavailableError
    from symloc.bench.provenance import RunClock
    from symloc.bench.results_file import write_run_results
    from symloc.bench.slam_bench import TARGETS, SlamBenchTask, run_bench_task, summarize
    from symloc.bench.slam_runs import log_name
    from symloc.bench.sweep import run_sweep
    from symloc.figures.slam import slam_bench_figure
    from symloc.sim.odometry_noise import ODOMETRY_REGIMES

    logs = _logs(args)
    peers: list[tuple[str, str]] = []
    peer_notes: list[str] = []
    for name in args.peers:
        if args.peer_src is None:
            peer_notes.append(
                f"{name}: skipped (no --peer-src: give an openslam_gmapping checkout)"
            )
            continue
        try:
            built = GMappingPeer.build(args.peer_src, build_dir=args.peer_build)
        except PeerUnavailableError as err:
            peer_notes.append(f"{name}: skipped ({err})")
            continue
        peers.append((name, str(built.binary)))
    regime = ODOMETRY_REGIMES.get(args.odometry)
    load = os.getloadavg()
    config = {
        "command": "symloc bench slam " + " ".join(sys.argv[3:] if len(sys.argv) > 3 else []),
        "date": datetime.datetime.now().isoformat(timespec="seconds"),
        "logs": [str(p) for p in logs],
        "seeds": args.seeds,
        "odometry": regime.describe() if regime is not None else "the log's own",
        "odometry_seed": "SeedSequence([seed, crc32(log name)])",
        "symloc": "default SlamParams (one configuration for every log)",
        "peers": [n for n, _ in peers],
        "peer_notes": peer_notes,
        "workers": args.workers,
        "load_average_at_start": [round(v, 2) for v in load],
        "cpu_count": os.cpu_count(),
    }
    print("# symloc bench slam")
    for k, v in config.items():
        print(f"#   {k}: {v}")
    for note in peer_notes:
        print(f"peer {note}")
    sys.stdout.flush()
    tasks = [
        SlamBenchTask(
            str(p),
            s,
            args.odometry,
            tuple(peers),
            max_scans=args.max_scans,
            timeout=args.timeout,
        )
        for p in logs
        for s in args.seeds
    ]

    def _progress(i: int, row: dict[str, Any]) -> None:
        if "skipped" in row:
            print(f"  {row['log']} seed {row['seed']}: skipped: {row['skipped']}")
        else:
            parts = []
            for sname, e in row["systems"].items():
                if "error" in e:
                    parts.append(f"{sname} ERROR {e['error'].splitlines()[0]}")
                else:
                    parts.append(
                        f"{sname} ATE {_fmt(e.get('ate_rmse_m'))} m (max {_fmt(e.get('ate_max_m'), '.2f')})"
                        f" {_fmt(e.get('peak_rss_mb'), '.0f')} MB"
                    )
            print(f"  {row['log']} seed {row['seed']}: " + "; ".join(parts))
        sys.stdout.flush()

    clock = RunClock()
    rows = run_sweep(run_bench_task, tasks, workers=args.workers, ray=args.ray, on_result=_progress)
    summary = summarize(rows, args.odometry)
    load_end = os.getloadavg()
    systems = ["symloc", *[n for n, _ in peers]]
    print()
    table = [
        [
            "log",
            "runs",
            *[f"{n} ATE mean / worst / max err [m]" for n in systems],
            "peak MB " + " / ".join(systems),
            "x real time (CPU) " + " / ".join(systems),
            "symloc loops acc / rej",
            "doubtful",
        ]
    ]
    for lg in sorted(summary["logs"]):
        per = summary["logs"][lg]
        sl = per.get("symloc", {})
        row = [lg, str(sl.get("runs", 0))]
        for sname in systems:
            e = per.get(sname, {})
            cell = (
                f"{_fmt(e.get('ate_mean_m'))} / {_fmt(e.get('ate_worst_m'))}"
                f" / {_fmt(e.get('max_error_m'), '.2f')}"
            )
            if e.get("errors"):
                cell += f" ({e['errors']} failed)"
            row.append(cell)
        row.append(" / ".join(_fmt(per.get(n, {}).get("peak_rss_mb"), ".0f") for n in systems))
        row.append(
            " / ".join(_fmt(per.get(n, {}).get("realtime_factor_cpu"), ".0f") for n in systems)
        )
        row.append(
            f"{_fmt(sl.get('loops_accepted'), '.0f')} / {_fmt(sl.get('loops_rejected'), '.0f')}"
        )
        row.append(str(sl.get("doubtful_runs", 0)))
        table.append(row)
    widths = [max(len(r[c]) for r in table) for c in range(len(table[0]))]
    for line in table:
        print(" | ".join(v.ljust(w) for v, w in zip(line, widths, strict=True)))
    for r in rows:
        if "skipped" in r:
            print(f"{r['log']} seed {r['seed']}: skipped: {r['skipped']}")
    t = summary["targets"]
    print()
    print(f"targets ({args.odometry}): every pair {t['pair_rule']}:", end=" ")
    print(
        "all pass"
        if not t["pairs_failed"]
        else f"{len(t['pairs_failed'])} of {t['pairs']} fail: {', '.join(t['pairs_failed'])}"
    )
    print(
        f"  median ATE over pairs {_fmt(t['median_ate_m'])} m (target < {t['median_target_m']}):"
        f" {'pass' if t['median_ok'] else 'MISS'}"
    )
    print(
        f"  peak memory < {t['memory_limit_mb']:.0f} MB: "
        + ("pass" if not t["logs_over_memory"] else "MISS on " + ", ".join(t["logs_over_memory"]))
    )
    print(
        f"  >= {t['min_realtime']:.0f}x real time (CPU) where stamps exist: "
        + (
            "pass"
            if not t["logs_below_realtime"]
            else "MISS on " + ", ".join(t["logs_below_realtime"])
        )
    )
    print(f"# load average at end: {[round(v, 2) for v in load_end]}")
    out = Path(args.out)
    target = TARGETS.get(args.odometry, TARGETS["realistic"])["median_ate"]
    png = slam_bench_figure(
        summary,
        out / f"slam_bench_{args.odometry}.png",
        title=f"symloc bench slam, odometry {args.odometry}, seeds {args.seeds}",
        target=float(target),
    )
    data = {"config": config, "rows": rows, "summary": summary, "load_average_at_end": load_end}
    paths = [write_json(out / f"slam_bench_{args.odometry}.json", data)]
    if args.json is not None:
        paths.append(write_json(args.json, data))
    if args.results is not None:
        settings = {k: v for k, v in config.items() if k not in ("command", "date")}
        settings["logs"] = [log_name(p) for p in logs]
        paths.append(
            write_run_results(
                args.results,
                argv=getattr(args, "argv", []),
                clock=clock,
                settings=settings,
                figures=summary,
                workers=args.workers,
            )
        )
    print("wrote " + ", ".join(str(p) for p in [*paths, png]))
    return 0
