"""Benchmark: map preprocessing on a 30-million-cell map (distance and surface fields).

A generated 6,000 x 5,000 map at 0.05 m (offices 4 m wide, walls three cells thick, doors);
each field is computed in a fresh process, which prints its CPU time [s], the process's peak
resident memory and its resident memory before the work [MiB] (VmHWM / VmRSS: not the
parent's).

Run: ``python benchmarks/bench_fields.py [--rows 6000 --cols 5000] [--seed S]``

``--replay DIR`` measures ``symloc replay`` instead (issue 31: a legal 8,192 x 8,192 map, the
map-file cap, peaked at 3.2 GB): the office map is saved in DIR as ``map.yaml`` with a ROS 2
bag of ``--scans`` scans ray-cast in it (a robot turning on the spot in one office; no
initial pose, so the node localizes globally), and ``symloc replay DIR/bag --map DIR/map.yaml --out DIR/out`` runs in a child
process; printed: its peak resident memory (``ru_maxrss`` of the child), its wall time, and
the SHA-256 of ``replay_scans.csv`` and ``replay_scans.tum`` (the same numbers before and after
a memory change = the same results). ``--rows``/``--cols`` default to 8192 there.

    python benchmarks/bench_fields.py --replay /tmp/big [--rows 8192 --cols 8192] [--scans 20]

``--results PATH`` also writes the figures as a results file with the command, commit, date,
machine and load (the README's: ``docs/results/bench_fields.json`` for the fields,
``docs/results/bench_fields_replay.json`` for ``--replay``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import resource
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

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
    """In this (fresh) process: compute one field and print its CPU time and memory, then the
    same as a JSON line for the parent."""
    grid = office_map(rows, cols, seed)
    base = status_mib("VmRSS")
    t0 = time.process_time()
    if which == "distance":
        distance_field(grid, 2.0)
    else:
        surface_distance_field(grid, 1.0)
    cpu = time.process_time() - t0
    peak = status_mib("VmHWM")
    print(f"{which:>8} field | {cpu:6.2f} s CPU | peak {peak:7.1f} MiB, before {base:6.1f} MiB")
    row = {"field": which, "cpu_s": round(cpu, 3), "peak_mib": round(peak, 1)}
    print(json.dumps(row | {"before_mib": round(base, 1)}))


def cast_scan(grid: OccupancyGrid, pose: np.ndarray, beams: int, max_range: float) -> np.ndarray:
    """Ranges [m] of ``beams`` beams over 360 deg from ``pose`` (x [m], y [m], theta [rad]),
    marched in steps of half a cell to the first occupied cell; ``max_range`` where none."""
    res = grid.resolution
    steps = np.arange(0.0, max_range, res / 2)
    angles = pose[2] - math.pi + np.arange(beams) * (2 * math.pi / beams)
    x = pose[0] + np.cos(angles)[:, None] * steps - grid.origin[0]
    y = pose[1] + np.sin(angles)[:, None] * steps - grid.origin[1]
    col = np.clip((x / res).astype(int), 0, grid.data.shape[1] - 1)
    row = np.clip((y / res).astype(int), 0, grid.data.shape[0] - 1)
    hit = grid.data[row, col] >= 50
    first = np.where(hit.any(axis=1), hit.argmax(axis=1), len(steps) - 1)
    return np.where(hit.any(axis=1), steps[first], max_range)


def replay_peak(folder: Path, rows: int, cols: int, seed: int, scans: int) -> dict[str, Any]:
    """Write the map and bag into ``folder``, run ``symloc replay`` in a child, print its peak;
    returns the figures (exit code, peak RSS [MiB], wall time [s], output digests)."""
    from symloc.grid.map_io import save_map
    from symloc.io.rosbag import BagWriter
    from symloc.odometry import OdometryReading
    from symloc.scan import LaserScan

    folder.mkdir(parents=True, exist_ok=True)
    grid = office_map(rows, cols, seed)
    yaml = save_map(grid, folder / "map")
    bag = folder / "bag"
    if not bag.exists():
        beams = 360
        with BagWriter(bag, "ros2") as w:
            for i in range(scans):
                t = 1.0 + 0.2 * i
                pose = np.array([(50 + 40) * 0.05, (50 + 40) * 0.05 + 0.1, 0.05 * i])
                w.write_odometry(OdometryReading(pose, t))
                ranges = cast_scan(grid, pose, beams, 8.0)
                w.write_scan(LaserScan(-math.pi, 2 * math.pi / beams, 0.1, 8.0, ranges, stamp=t))
    occupied = int(np.count_nonzero(grid.data >= 50))
    del grid
    out = folder / "out"
    cmd = [sys.executable, "-m", "symloc.cli.main", "replay", str(bag), "--map", str(yaml)]
    cmd += ["--out", str(out)]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0  # KiB on Linux
    print(f"replay exit {proc.returncode}: {rows} x {cols} map, {scans} scans")
    if proc.returncode not in (0, 3):
        print(proc.stderr[-2000:])
    digests = {}
    for name in ("replay_scans.csv", "replay_scans.tum"):
        f = out / name
        digest = hashlib.sha256(f.read_bytes()).hexdigest()[:16] if f.exists() else "missing"
        digests[name] = digest
        print(f"  {name}: sha256 {digest}")
    print(f"  peak RSS {peak:.0f} MiB, wall {wall:.1f} s")
    return {
        "exit_code": proc.returncode,
        "cells": [rows, cols],
        "occupied_cells": occupied,
        "scans": scans,
        "peak_rss_mib": round(peak, 1),
        "wall_s": round(wall, 2),
        "sha256_16": digests,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=None, help="default 6000 (8192 with --replay)")
    ap.add_argument("--cols", type=int, default=None, help="default 5000 (8192 with --replay)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--replay", type=Path, default=None, help="folder for the map, bag, output")
    ap.add_argument("--scans", type=int, default=20, help="scans in the --replay bag")
    ap.add_argument("--one", choices=["distance", "surface"], help=argparse.SUPPRESS)
    ap.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write a results file (the README's: docs/results/bench_fields.json, "
        "docs/results/bench_fields_replay.json with --replay)",
    )
    args = ap.parse_args()
    big = args.replay is not None
    args.rows = args.rows or (8192 if big else 6000)
    args.cols = args.cols or (8192 if big else 5000)
    if args.one:
        one(args.one, args.rows, args.cols, args.seed)
        return 0
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    settings = {"rows": args.rows, "cols": args.cols, "seed": args.seed, "resolution_m": 0.05}
    if big:
        figures = replay_peak(args.replay, args.rows, args.cols, args.seed, args.scans)
        if args.results is not None:
            write(args.results, clock, settings, {"rows": [figures]})
        return 0
    load = " ".join(f"{v:.2f}" for v in os.getloadavg())
    print(
        f"# bench_fields seed={args.seed}: {args.rows} x {args.cols} cells"
        f" ({args.rows * args.cols / 1e6:.0f} M) at 0.05 m; load average {load}"
    )
    rows = []
    for which in ("distance", "surface"):
        cmd = [sys.executable, __file__, "--one", which, "--rows", str(args.rows)]
        cmd += ["--cols", str(args.cols), "--seed", str(args.seed)]
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        print(out.splitlines()[0], flush=True)
        rows.append(json.loads(out.splitlines()[-1]))
    if args.results is not None:
        write(args.results, clock, settings, {"rows": rows})
    return 0


def write(path: Path, clock: Any, settings: dict[str, Any], figures: dict[str, Any]) -> None:
    """Write the results file ``path`` of this run (:func:`write_bench_results`)."""
    from symloc.bench.results_file import write_bench_results

    written = write_bench_results(path, clock=clock, settings=settings, figures=figures)
    print(f"wrote {written}")


if __name__ == "__main__":
    raise SystemExit(main())
