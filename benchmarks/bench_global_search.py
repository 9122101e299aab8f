"""Benchmark: the branch-and-bound global scan-to-map search (:mod:`symloc.mcl.global_search`).

One search = one scan against the whole map, every heading (default settings: 5 cm lattice,
0.1 m hit tolerance, the angular step from the scan's range capped at 15 m, min score 0.5,
margin 0.1). Per map, the median over the scans of:

- the search's CPU time [ms] (``time.process_time``: every thread of the search; it splits the headings over the cores)
  and wall time [ms];
- the nodes evaluated, the distinct candidates, how often the search completed, and how often
  the true pose is among the candidates (within 0.2 m and 2 degrees; 0.3 m / 3 deg on CARMEN,
  whose corrected poses are a SLAM estimate).

The map's precomputation (pyramid, obstacle distance; once per map) is timed separately.

Maps:

(a) ``room``: a 10 m x 10 m L-shaped room and a 10 m square with one box (bench size, 0.05 m),
    realistic RPLIDAR A2 scans from ``symloc.sim`` at random free poses;
(b) ``carmen``: each log of ``--carmen DIR`` (default ``$SYMLOC_SHARED_DATA/carmen`` or
    ``../shared/data/carmen``, :func:`symloc.bench.shared_data.find_carmen_dir`;
    ``--logs``, default intel) mapped from its scans at the corrected poses as
    ``symloc experiment amcl-carmen`` does (log-odds, 5 cm), its own scans (every
    ``len // scans``-th) searched;
(c) ``large``: ``bench_amcl.large_world``, 5,200 x 5,200 cells at 0.05 m (260 m square of
    identical offices and corridors), 360-beam 30 m scans along its drive, pyramid depth
    ``--large-depth`` (default 9: blocks of 25.6 m, fewer roots); the budgets (``max_nodes``,
    ``max_seconds``) are what bound it: the map repeats itself every 20 m, so thousands of
    poses explain a scan.

``--results PATH`` also writes one row per map (the figures above) as a results file with the
command, commit, date, machine and load (the README's: ``docs/results/bench_global_search.json``).

Run: ``PYTHONPATH=src python benchmarks/bench_global_search.py [--scans 20] [--carmen DIR]
[--logs intel fr079] [--maps room carmen large] [--seed 0] [--results PATH]``
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from symloc.geometry import wrap_angle
from symloc.grid import OccupancyGrid
from symloc.grid.fields import MapFields
from symloc.lidar_spec import RPLIDAR_A2
from symloc.mcl.global_search import GlobalSearch, GlobalSearchConfig, GlobalSearchResult
from symloc.scan import LaserScan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.regimes import get_regime
from symloc.sim.rooms import add_furniture, l_shaped_room, regular_polygon_room

sys.path.insert(0, str(Path(__file__).resolve().parent))


def found(res: GlobalSearchResult, truth: np.ndarray, xy: float, th: float) -> bool:
    return any(
        math.hypot(*(c.pose[:2] - truth[:2])) <= xy
        and abs(float(wrap_angle(c.pose[2] - truth[2]))) <= th
        for c in res.candidates
    )


def run(
    name: str,
    grid: OccupancyGrid,
    cases: list[tuple[LaserScan, np.ndarray, np.ndarray | None]],
    cfg: GlobalSearchConfig,
    tol: tuple[float, float],
) -> dict[str, Any]:
    """Search every case's scan on ``grid``; print the map's line and return it as a row
    (times in ms, the precomputation in s)."""
    c0 = time.process_time()
    search = GlobalSearch(MapFields(grid), cfg)
    pre_cpu = time.process_time() - c0
    cpu, wall, nodes, ncand, complete, hit = [], [], [], [], [], []
    reasons: list[str] = []
    for scan, truth, mount in cases:
        c0 = time.process_time()
        res = search.search(scan, laser_pose=mount)
        cpu.append(time.process_time() - c0)
        wall.append(res.seconds)
        nodes.append(res.n_nodes)
        ncand.append(res.n_distinct)
        complete.append(res.complete)
        if res.reason:
            reasons.append(res.reason.split(":")[0] if "budget" in res.reason else res.reason)
        hit.append(found(res, truth, *tol))
    mb = search.pyramid.nbytes / 2**20
    print(
        f"{name:<22} {grid.height:>5}x{grid.width:<5} pre {pre_cpu:6.2f} s cpu ({mb:5.0f} MiB) |"
        f" search median {1e3 * np.median(cpu):8.1f} ms cpu {1e3 * np.median(wall):8.1f} ms wall"
        f" (max {1e3 * max(cpu):7.1f}) | nodes {int(np.median(nodes)):>8} |"
        f" distinct {np.median(ncand):4.0f} | complete {sum(complete)}/{len(cases)} |"
        f" truth found {sum(hit)}/{len(cases)} | headings {res.n_headings}",
        flush=True,
    )
    if reasons:
        print(f"{'':<22} incomplete: {dict(Counter(reasons))}", flush=True)
    return {
        "map": name,
        "cells": [grid.height, grid.width],
        "precompute_cpu_s": round(pre_cpu, 3),
        "pyramid_mib": round(mb, 1),
        "scans": len(cases),
        "cpu_ms_median": round(1e3 * float(np.median(cpu)), 2),
        "wall_ms_median": round(1e3 * float(np.median(wall)), 2),
        "cpu_ms_max": round(1e3 * max(cpu), 2),
        "nodes_median": int(np.median(nodes)),
        "distinct_median": float(np.median(ncand)),
        "complete": int(sum(complete)),
        "truth_found": int(sum(hit)),
        "tolerance": [tol[0], round(math.degrees(tol[1]), 3)],
        "headings": int(res.n_headings),
        "incomplete": dict(Counter(reasons)),
        "max_seconds": cfg.max_seconds,
        "max_nodes": cfg.max_nodes,
    }


def room_cases(
    room_builder: str, n: int, seed: int
) -> tuple[OccupancyGrid, list[tuple[LaserScan, np.ndarray, np.ndarray | None]]]:
    if room_builder == "l10":
        room = l_shaped_room(10.0)
    else:
        room = add_furniture(regular_polygon_room(4, 5.0 * math.sqrt(2.0)), boxes=1, rng=seed)
    grid = world_to_grid(room.world, 0.05)
    rng = np.random.default_rng(seed)
    lidar = get_regime("realistic").lidar(RPLIDAR_A2, rng)
    free = np.argwhere(MapFields.of(grid).obstacle_distance() > 0.4)
    free = free[grid.free_mask[free[:, 0], free[:, 1]]]
    cases = []
    for _ in range(n):
        xy = grid.cell_to_world(free[rng.integers(len(free))])[0] + rng.uniform(-0.02, 0.02, 2)
        truth = np.array([xy[0], xy[1], rng.uniform(-np.pi, np.pi)])
        cases.append((lidar.scan(room.world, truth), truth, None))
    return grid, cases


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scans", type=int, default=20, help="scans per map")
    ap.add_argument("--carmen", default=None, help="folder of CARMEN logs")
    ap.add_argument("--logs", nargs="+", default=["intel"])
    ap.add_argument("--maps", nargs="+", default=["room", "carmen", "large"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--large-depth", type=int, default=9, help="pyramid depth on the large map")
    ap.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write a results file (the README's: docs/results/bench_global_search.json)",
    )
    args = ap.parse_args()
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    rows: list[dict[str, Any]] = []
    print(f"# seed {args.seed}, {args.scans} scans per map")
    cfg = GlobalSearchConfig()
    print(f"# {cfg}")
    # warm the compiled kernels (loaded from numba's disk cache; compiled on a first run)
    g0, c0 = room_cases("l10", 1, 0)
    GlobalSearch(g0, cfg).search(c0[0][0])

    for kind in ("l10", "square10+box") if "room" in args.maps else ():
        grid, cases = room_cases(kind, args.scans, args.seed)
        rows.append(run(f"room {kind}", grid, cases, cfg, (0.2, math.radians(2.0))))

    from symloc.bench.shared_data import find_carmen_dir

    folder = Path(args.carmen) if args.carmen else find_carmen_dir()
    if "carmen" not in args.maps:
        pass
    elif folder is not None and folder.is_dir():
        from symloc.experiments.amcl_carmen import build_map
        from symloc.io.carmen import read_carmen

        with tempfile.TemporaryDirectory() as tmp:
            for name in args.logs:
                path = folder / f"{name}-corrected.log.gz"
                if not path.is_file():
                    print(f"# {name}: {path} not found, skipped")
                    continue
                log = read_carmen(path)
                grid = build_map(log, cache=Path(tmp) / f"map_{name}.npz")
                every = max(1, len(log.scans) // args.scans)
                picked = log.scans[::every][: args.scans]
                cases = [(s.scan, np.asarray(s.laser_pose, dtype=np.float64), None) for s in picked]
                rows.append(run(f"carmen {name}", grid, cases, cfg, (0.3, math.radians(3.0))))
    else:
        print(f"# no CARMEN folder at {folder}: skipped")

    if "large" in args.maps:
        from bench_amcl import large_world

        grid, truth, _, scans = large_world(args.seed)
        every = max(1, len(scans) // args.scans)
        cases = [(scans[i], truth[i], None) for i in range(0, len(scans), every)][: args.scans]
        rows.append(
            run(
                f"large 260 m depth {args.large_depth}",
                grid,
                cases,
                dataclasses.replace(cfg, depth=args.large_depth),
                (0.2, math.radians(2.0)),
            )
        )
    if args.results is not None:
        from symloc.bench.results_file import write_bench_results

        settings = {
            "scans": args.scans,
            "seed": args.seed,
            "maps": args.maps,
            "logs": args.logs,
            "large_depth": args.large_depth,
            "config": dataclasses.asdict(cfg),
        }
        written = write_bench_results(
            args.results, clock=clock, settings=settings, figures={"rows": rows}
        )
        print(f"wrote {written}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
