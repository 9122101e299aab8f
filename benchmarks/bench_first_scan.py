"""Benchmark: how long a fresh node process is blocked before its first pose.

A recorded simulated run (``symloc.bench.sim_record.record_sim_run``: map, odometry, scans,
images, the node's parameters) is replayed through the node logic (:class:`~symloc.ros.core.
NodeCore`, what the ROS 2 node runs per message) in a *new process* per measurement, so that
nothing compiled or imported by a previous run helps. Reported per process, wall and CPU:

- ``configure``: building the node core, setting the map and warming the compiled kernels up
  (:func:`symloc.mcl.warmup.warm_up`; ``--no-warm-up``: without) -- what the lifecycle's
  ``on_configure`` runs before the node is active;
- ``first scan``: the first scan's call (the localizer's first filter update, its first
  verdict, the first symmetry judgement);
- ``second scan`` for comparison.

Two cases: ``cold`` -- numba's on-disk cache empty (``NUMBA_CACHE_DIR`` a new folder: a fresh
install; every kernel is compiled in this process), then ``warm`` -- the same folder again (a
second start: the kernels load from the cache).

Each child also says whether symloc's per-scan kernels ran from their ahead-of-time build
(:mod:`symloc.mcl.aot`) or numba's JIT. ``--results PATH`` writes every process's figures as a
results file with the command, commit, date, machine and load (the README's:
``docs/results/bench_first_scan.json``).

Run: ``python benchmarks/bench_first_scan.py [--seed 0] [--repeats 2] [--no-warm-up]
[--results PATH]``
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

_LOG = logging.getLogger("bench_first_scan")


def child(bag: Path, params_path: Path, *, warm: bool) -> int:
    """In a fresh process: configure the node core (with the kernels' warm-up, as the node's
    ``on_configure``, when ``warm``), then time its first two scans."""
    t0, c0 = time.perf_counter(), time.process_time()
    from symloc.io.rosbag import read_bag
    from symloc.ros.core import NodeCore
    from symloc.ros.params import NodeParams

    t_imp, c_imp = time.perf_counter() - t0, time.process_time() - c0
    params = NodeParams.from_yaml(params_path)
    t0, c0 = time.perf_counter(), time.process_time()
    core = NodeCore(params)
    messages = list(read_bag(bag, on_error="skip"))
    for m in messages:  # the map comes first in the recording
        if m.kind == "map":
            core.set_map(m.value)
            break
    if warm:
        from symloc.mcl.warmup import warm_up

        warm_up(params.amcl)
    t_cfg, c_cfg = time.perf_counter() - t0, time.process_time() - c0
    scans: list[tuple[float, float]] = []
    for m in messages:
        if m.kind == "scan":
            t0, c0 = time.perf_counter(), time.process_time()
            out = core.add_scan(m.value)
            if out.used:
                scans.append((time.perf_counter() - t0, time.process_time() - c0))
                if len(scans) == 2:
                    break
        elif m.kind == "odom":
            core.add_odometry(m.value)
        elif m.kind == "image":
            core.add_image(m.value, m.stamp)
    from symloc.mcl import kernels

    print(
        json.dumps(
            {
                "import": [t_imp, c_imp],
                "configure": [t_cfg, c_cfg],
                "first": list(scans[0]),
                "second": list(scans[1]),
                "aot_kernels": bool(kernels.endpoint_table_sum.ahead_of_time),
            }
        )
    )
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=2, help="processes per case")
    ap.add_argument(
        "--no-warm-up",
        dest="warm",
        action="store_false",
        help="configure without the kernels' warm-up (the node before it did one)",
    )
    ap.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write a results file (the README's: docs/results/bench_first_scan.json)",
    )
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child(Path(args.child[0]), Path(args.child[1]), warm=args.warm)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    with tempfile.TemporaryDirectory(prefix="symloc-bench-first-scan-") as tmp:
        rows = measure(Path(tmp), args)
    if args.results is not None:
        from symloc.bench.results_file import write_bench_results

        settings = {"seed": args.seed, "repeats": args.repeats, "warm_up": args.warm}
        written = write_bench_results(
            args.results, clock=clock, settings=settings, figures={"rows": rows}
        )
        _LOG.info("wrote %s", written)
    return 0


def measure(work: Path, args: argparse.Namespace) -> list[dict[str, Any]]:
    """Record the simulated run in ``work`` and time the node's start in fresh processes
    (``args``: seed, repeats, warm); log the table and return its rows."""
    from symloc.bench.sim_record import record_sim_run

    rows: list[dict[str, Any]] = []
    rec = record_sim_run(work / "run", seed=args.seed, max_time=10.0)
    _LOG.info(
        "# recorded %s; load %.2f; %d cores; %s",
        rec.bag,
        os.getloadavg()[0],
        os.cpu_count(),
        "warm-up at configure" if args.warm else "no warm-up",
    )
    _LOG.info(
        "%-5s %-3s | %-17s | %-17s | %-17s (wall s / cpu s)",
        "cache",
        "run",
        "configure",
        "first scan",
        "second scan",
    )
    cache = work / "numba-cache"
    cache.mkdir()
    for case in ("cold", "warm"):
        for k in range(args.repeats if case == "warm" else 1):
            env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
            cmd = [
                sys.executable,
                str(Path(__file__).resolve()),
                "--child",
                str(rec.bag),
                str(rec.params_path),
            ]
            cmd += [] if args.warm else ["--no-warm-up"]
            out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
            r = json.loads(out.stdout.strip().splitlines()[-1])
            _LOG.info(
                "%-5s %-3d | %7.2f / %7.2f | %7.2f / %7.2f | %7.3f / %7.3f",
                case,
                k,
                *r["configure"],
                *r["first"],
                *r["second"],
            )
            rows.append(
                {
                    "cache": case,
                    "run": k,
                    **{
                        f"{what}_{clock_}_s": round(r[what][i], 4)
                        for what in ("import", "configure", "first", "second")
                        for i, clock_ in enumerate(("wall", "cpu"))
                    },
                    "aot_kernels": r["aot_kernels"],
                }
            )
    return rows


if __name__ == "__main__":
    raise SystemExit(main())
