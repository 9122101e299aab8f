"""Benchmark the symmetry judgement: one ``judge_symmetry`` call on a 360- and an 800-beam scan.

Scans: the paper's 15 m scanner (360 beams, PAPER_15M) and the RPLIDAR A2 (800 beams), each in
a regular hexagon (G-V 5 m, the polygon path: split-and-merge, corners, rotation test), a
round room (G-V 5 m, the circle path) and a square with a box (the asymmetric path), from 32
positions with random headings. Also times the paper's Algorithm 1 as written. Prints median
wall and CPU time per call [ms] over all scans, the largest per-scan median CPU time ("worst
ms": the judgement of the slowest scan, each scan timed ``--rounds`` times), and the mean
number of Python-level function calls (Python and C, NumPy's included) per judgement, which
does not depend on the machine's load: on a small scan the judgement's cost is mostly the
per-call overhead of NumPy. Target (issues 3 and 30): under 1 ms on every scan.

Run: ``python benchmarks/bench_symmetry.py [--repeats R] [--seed S] [--rounds N] [--results
PATH]`` (``--results``: also write a results file, the README's is
``docs/results/bench_symmetry.json``, with every row, the command, commit, date, machine and
load; ``python -m symloc.readme`` renders the README's figures from it). The README's row runs
it on one core: ``taskset -c 0 python benchmarks/bench_symmetry.py --seed 0``.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from symloc.scan import LaserScan
from symloc.sim.lidar import PAPER_15M, RPLIDAR_A2, simulate_scan
from symloc.sim.rooms import build_room
from symloc.symmetry import SymmetryConfig, algorithm1, judge_symmetry


def median_ms(fn: Callable[[int], object], repeats: int) -> tuple[float, float]:
    """Median wall and CPU time [ms] of ``fn(i)`` over ``repeats`` calls, after warm-up.

    On a shared machine the wall time includes waiting for a core; the CPU time does not.
    """
    for i in range(3):
        fn(i)
    wall, cpu = [], []
    for i in range(repeats):
        t0 = time.perf_counter()
        c0 = time.process_time()
        fn(i)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - t0)
    return float(np.median(wall) * 1e3), float(np.median(cpu) * 1e3)


def worst_scan_ms(fn: Callable[[int], object], n: int, rounds: int) -> float:
    """The largest, over scans ``i = 0..n-1``, of the median CPU time [ms] of ``fn(i)``.

    The scans are judged in turn ``rounds`` times (after one warm-up round), so that a change
    of the machine's load hits every scan alike; the target is per scan, not over all scans.
    """
    for i in range(n):
        fn(i)
    cpu = np.empty((rounds, n))
    for r in range(rounds):
        for i in range(n):
            c0 = time.process_time()
            fn(i)
            cpu[r, i] = time.process_time() - c0
    return float(np.max(np.median(cpu, axis=0)) * 1e3)


def calls_per_call(fn: Callable[[int], object], n: int) -> float:
    """Mean number of Python and C function calls made by ``fn(i)``, i = 0..n-1."""
    for i in range(n):
        fn(i)  # warm-up: first calls import and cache
    count = 0

    def prof(_frame: object, event: str, _arg: object) -> None:
        nonlocal count
        if event in ("call", "c_call"):
            count += 1

    sys.setprofile(prof)
    try:
        for i in range(n):
            fn(i)
    finally:
        sys.setprofile(None)
    return count / n


def _judge_nth(scans: list[LaserScan], cfg: SymmetryConfig) -> Callable[[int], object]:
    """``fn(i)`` judging scan ``i`` modulo the number of scans."""

    def fn(i: int) -> object:
        return judge_symmetry(scans[i % len(scans)], config=cfg)

    return fn


def _algorithm1_nth(scans: list[LaserScan], cfg: SymmetryConfig) -> Callable[[int], object]:
    """``fn(i)`` running the paper's Algorithm 1 (n = 4) on scan ``i`` modulo the count."""

    def fn(i: int) -> object:
        return algorithm1(scans[i % len(scans)], n=4, config=cfg)

    return fn


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=300, help="timed calls per figure")
    parser.add_argument("--seed", type=int, default=0, help="random seed (printed)")
    parser.add_argument(
        "--rounds", type=int, default=15, help="timed calls per scan for the worst-scan figure"
    )
    parser.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write a results file (the README's: docs/results/bench_symmetry.json)",
    )
    args = parser.parse_args()
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    rows: list[dict[str, Any]] = []
    rng = np.random.default_rng(args.seed)
    print(f"# bench_symmetry seed={args.seed} repeats={args.repeats} rounds={args.rounds}")
    rooms = {
        "hexagon": build_room("hexagon", 5.0, lab=False),
        "circle": build_room("circle", 5.0, lab=False),
        "square+box": build_room("square", 5.0, lab=False, furniture=1, rng=args.seed),
    }
    print(
        f"{'scan':<26} {'room':<11} {'verdict':<22} {'wall ms':>8} {'cpu ms':>8} {'calls':>7}"
        f" {'worst ms':>9}"
    )
    for preset in (PAPER_15M, RPLIDAR_A2):
        cfg = SymmetryConfig.from_lidar(preset)
        for name, room in rooms.items():
            pos = room.positions_inside(32)
            scans = [
                simulate_scan(room.world, np.r_[p, rng.uniform(-np.pi, np.pi)], preset, rng)
                for p in pos
            ]
            verdict = judge_symmetry(scans[0], config=cfg)
            label = f"{verdict.kind} k={verdict.order}"
            fn = _judge_nth(scans, cfg)
            wall, cpu = median_ms(fn, args.repeats)
            calls = calls_per_call(fn, len(scans))
            worst = worst_scan_ms(fn, len(scans), args.rounds)
            beams = f"{preset.name} ({preset.n_beams} beams)"
            print(
                f"{beams:<26} {name:<11} {label:<22} {wall:>8.3f} {cpu:>8.3f} {calls:>7.0f}"
                f" {worst:>9.3f}"
            )
            rows.append(
                {
                    "lidar": preset.name,
                    "beams": preset.n_beams,
                    "room": name,
                    "method": "judge_symmetry",
                    "verdict": label,
                    "wall_ms": round(wall, 4),
                    "cpu_ms": round(cpu, 4),
                    "calls": round(calls, 1),
                    "worst_cpu_ms": round(worst, 4),
                }
            )
        wall, cpu = median_ms(_algorithm1_nth(scans, cfg), args.repeats)
        print(
            f"{beams:<26} {'square+box':<11} {'Algorithm 1 (paper)':<22} {wall:>8.3f} {cpu:>8.3f}"
        )
        rows.append(
            {
                "lidar": preset.name,
                "beams": preset.n_beams,
                "room": "square+box",
                "method": "algorithm1",
                "wall_ms": round(wall, 4),
                "cpu_ms": round(cpu, 4),
            }
        )
    if args.results is not None:
        from symloc.bench.results_file import write_bench_results

        settings = {"seed": args.seed, "repeats": args.repeats, "rounds": args.rounds}
        written = write_bench_results(
            args.results,
            clock=clock,
            settings=settings,
            figures={"rows": rows, "units": "ms per judgement (median; worst: per-scan median)"},
        )
        print(f"wrote {written}")


if __name__ == "__main__":
    main()
