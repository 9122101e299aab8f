"""``symloc bench symmetry``: Algorithm 1 from random poses in many worlds, against the truth."""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import Any

from symloc.cli import options
from symloc.cli.bench_commands._common import add_sweep_arguments, write_json

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    """Add ``symmetry`` to ``symloc bench``."""
    from symloc.lidar_spec import PRESETS
    from symloc.sim.generator import FAMILIES
    from symloc.sim.regimes import REGIMES

    parser: argparse.ArgumentParser = subparsers.add_parser(
        "symmetry",
        help="the symmetry judgement (Algorithm 1) from random poses in many worlds, against "
        "the order computed from each world's geometry",
    )
    parser.add_argument(
        "--families",
        nargs="+",
        default=None,
        metavar="NAME",
        help=f"generator families (default all: {', '.join(FAMILIES)}) or built-in rooms",
    )
    parser.add_argument("--world", nargs="+", default=None, metavar="FILE", help="world files")
    parser.add_argument(
        "--worlds", type=options.count, default=10, help="worlds per family (default 10)"
    )
    parser.add_argument("--split", choices=("dev", "test"), default="dev", help="world seeds")
    parser.add_argument(
        "--seeds",
        type=options.nonnegative_int,
        nargs="+",
        default=None,
        help="explicit world seeds",
    )
    parser.add_argument(
        "--poses", type=options.count, default=20, help="scans judged per world (20)"
    )
    parser.add_argument(
        "--lidar", choices=sorted(PRESETS), default="rplidar_a2", help="lidar (rplidar_a2)"
    )
    parser.add_argument("--regime", choices=REGIMES, default="ideal", help="sensor regime")
    add_sweep_arguments(parser, "bench symmetry")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from symloc.bench.sweep import run_sweep
    from symloc.bench.symmetry_sweep import SymmetryTask, run_symmetry_world, summarize_symmetry
    from symloc.bench.world_sources import family_refs, file_refs, split_seeds
    from symloc.errors import ConfigurationError
    from symloc.sim.generator import FAMILIES

    if args.worlds < 1 or args.poses < 1:
        raise ConfigurationError("--worlds and --poses: expected integers >= 1")
    seeds = args.seeds if args.seeds else split_seeds(args.split, args.worlds)
    refs = (
        file_refs(args.world, seeds)
        if args.world
        else family_refs(args.families or list(FAMILIES), seeds)
    )
    tasks = [
        SymmetryTask(ref, ref.seed, args.poses, lidar=args.lidar, regime=args.regime)
        for ref in refs
    ]
    settings = {
        "families": args.world or args.families or list(FAMILIES),
        "split": None if args.seeds else args.split,
        "world_seeds": seeds,
        "worlds": len(tasks),
        "poses_per_world": args.poses,
        "lidar": args.lidar,
        "regime": args.regime,
        "seed of a world's poses and scans": "its world seed",
    }
    print("# symloc bench symmetry")
    for key, value in settings.items():
        print(f"#   {key}: {value}")
    sys.stdout.flush()
    bar = tqdm(total=len(tasks), unit="world", desc="worlds", file=sys.stderr)
    t0 = time.perf_counter()
    worlds = run_sweep(
        run_symmetry_world,
        tasks,
        workers=args.workers,
        ray=args.ray,
        on_result=lambda _i, _w: bar.update(1),
    )
    bar.close()
    summary = summarize_symmetry(worlds)
    print()
    head = (
        f"{'family':<16} {'scans':>6} {'correct %':>9} {'false symmetric % [95% CI]':>28} "
        f"{'missed %':>8} {'unknown %':>9} {'centre p95':>10}"
    )
    print(head)
    print("-" * len(head))
    for r in summary:
        n = max(r["judgements"], 1)
        lo, hi = r["false_symmetric_ci95"]
        e = r["centre_error_p95_m"]
        fs = f"{100 * r['false_symmetric'] / n:.1f} [{100 * lo:.1f}, {100 * hi:.1f}]"
        ce = "-" if math.isnan(e) else f"{100 * e:.1f} cm"
        print(
            f"{r['family']:<16} {r['judgements']:>6} {100 * r['correct'] / n:>9.1f} {fs:>28} "
            f"{100 * r['missed'] / n:>8.1f} {100 * r['unknown'] / n:>9.1f} {ce:>10}"
        )
    args.out.mkdir(parents=True, exist_ok=True)
    doc = {"command": "symloc bench symmetry", "settings": settings, "summary": summary}
    doc["worlds"] = worlds
    path = write_json(args.out / "bench_symmetry.json", doc)
    if args.json is not None:
        write_json(args.json, doc)
    print(f"wrote {path}; wall time {time.perf_counter() - t0:.0f} s on {args.workers} worker(s)")
    return 0
