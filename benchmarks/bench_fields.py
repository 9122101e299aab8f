"""Benchmark: map preprocessing on a 30-million-cell map (distance and surface fields).

A generated 6,000 x 5,000 map at 0.05 m (offices 4 m wide, walls three cells thick, doors);
each field is computed in a fresh process, which prints its CPU time [s], the process's peak
resident memory and its resident memory before the work [MiB] (VmHWM / VmRSS: not the
parent's).

Run: ``python benchmarks/bench_fields.py [--rows 6000 --cols 5000] [--seed S]``
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from symloc.grid import OccupancyGrid
from symloc.grid.fields import distance_field, surface_distance_field


def office_map(rows: int, cols: int, seed: int) -> OccupancyGrid:
    """Offices 4 m wide (walls every 80 cells, three thick) with random doors, at 0.05 m."""
    rng = np.random.default_rng(seed)
    d = np.full((rows, cols), -1, np.int8)
    d[50:-50, 50:-50] = 0
    for r in range(50, rows - 50, 80):
        d[r : r + 3, 50:-50] = 100
    for c in range(50, cols - 50, 80):
        d[50:-50, c : c + 3] = 100
    for r in range(90, rows - 50, 80):
        for c in range(90, cols - 50, 400):
            if rng.random() < 0.5:
                d[r - 40 : r + 40, c : c + 3] = 0
    return OccupancyGrid(d, 0.05)


def status_mib(field: str) -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return float(line.split()[1]) / 1024.0
    return float("nan")


def one(which: str, rows: int, cols: int, seed: int) -> None:
    grid = office_map(rows, cols, seed)
    base = status_mib("VmRSS")
    t0 = time.process_time()
    if which == "distance":
        distance_field(grid, 2.0)
    else:
        surface_distance_field(grid, 1.0)
    cpu = time.process_time() - t0
    print(
        f"{which:>8} field | {cpu:6.2f} s CPU | peak {status_mib('VmHWM'):7.1f} MiB, before {base:6.1f} MiB"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=6000)
    ap.add_argument("--cols", type=int, default=5000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--one", choices=["distance", "surface"], help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        one(args.one, args.rows, args.cols, args.seed)
        return 0
    load = " ".join(f"{v:.2f}" for v in os.getloadavg())
    print(
        f"# bench_fields seed={args.seed}: {args.rows} x {args.cols} cells"
        f" ({args.rows * args.cols / 1e6:.0f} M) at 0.05 m; load average {load}"
    )
    for which in ("distance", "surface"):
        cmd = [sys.executable, __file__, "--one", which, "--rows", str(args.rows)]
        cmd += ["--cols", str(args.cols), "--seed", str(args.seed)]
        subprocess.run(cmd, check=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
