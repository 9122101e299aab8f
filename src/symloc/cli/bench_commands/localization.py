"""``symloc bench localization``: kidnapped and lost robots over many worlds, symloc vs AMCL."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

from symloc.cli import options
from symloc.cli.bench_commands._common import add_sweep_arguments, write_json

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    """Add ``localization`` to ``symloc bench``."""
    from symloc.bench.localization import MAPPING_REACH
    from symloc.bench.trial import DEFAULT_METHODS, METHODS, TRIAL_KINDS
    from symloc.bench.world_sources import BUILTIN_ROOMS
    from symloc.sim.generator import FAMILIES
    from symloc.sim.regimes import REGIMES

    parser: argparse.ArgumentParser = subparsers.add_parser(
        "localization",
        help="global localization and kidnapping over many worlds, each mapped anew: symloc "
        "and plain AMCL graded over the whole run",
        description="Every world is mapped anew with its own seed (laser SLAM + visual map), "
        "then each trial puts the robot down anywhere it fits (global) or carries it away "
        "while tracking (kidnap). A trial is confident wrong if any pose published as "
        "tracking, at any scan, is outside 0.1 m / 5 deg.",
    )
    parser.add_argument(
        "--families",
        nargs="+",
        default=None,
        metavar="NAME",
        help=f"world generator families (default all: {', '.join(FAMILIES)}) or built-in "
        f"rooms ({', '.join(BUILTIN_ROOMS)})",
    )
    parser.add_argument(
        "--world",
        nargs="+",
        default=None,
        metavar="FILE",
        help="world files (YAML, see docs/world_files.md) instead of --families",
    )
    parser.add_argument(
        "--worlds",
        type=options.count,
        default=3,
        help="worlds (mapping runs) per family (default 3)",
    )
    parser.add_argument(
        "--split",
        choices=("dev", "test"),
        default="dev",
        help="world seeds: dev (0, 1, ...; tune here) or test (1000000, ...; report here)",
    )
    parser.add_argument(
        "--seeds",
        type=options.nonnegative_int,
        nargs="+",
        default=None,
        help="explicit world seeds (overrides --split)",
    )
    options.add_trials(parser, default=10, what="trials per world")
    parser.add_argument(
        "--kinds",
        nargs="+",
        choices=TRIAL_KINDS,
        default=list(TRIAL_KINDS),
        help="trial kinds, alternated (default: global kidnap)",
    )
    parser.add_argument(
        "--methods",
        nargs="+",
        choices=METHODS,
        default=list(DEFAULT_METHODS),
        help="methods to run (default: symloc centre amcl). symloc: as shipped (deciding "
        "from where the robot stands, on keyframes recorded along the mapping trip); centre: "
        "the paper's path alone (AMCL, then the drive to the centre); amcl: nav2's filter "
        "alone; decide: deciding from where the robot stands, forced on",
    )
    parser.add_argument(
        "--map",
        choices=("slam", "raster"),
        default="slam",
        help="occupancy grid and visual-map poses from SLAM (default) or ground truth",
    )
    parser.add_argument(
        "--mapping-reach",
        type=options.mapping_reach,
        default=MAPPING_REACH,
        metavar="M",
        help="after its lap along the walls the mapping robot stops and looks around until no "
        "place it can reach is farther than M metres from where it was (default "
        f"{MAPPING_REACH:g}, the keyframes' reach: keyframes near every place; 0: the lap only)",
    )
    parser.add_argument(
        "--regime",
        choices=REGIMES,
        default="ideal",
        help="sensor regime of the robot (symloc.sim.regimes; default ideal)",
    )
    parser.add_argument(
        "--claim-timeout",
        type=options.sim_seconds,
        default=60.0,
        help="seconds to make a first claim (60)",
    )
    parser.add_argument(
        "--track-time",
        type=options.sim_seconds,
        default=20.0,
        help="seconds driven after the first claim (20)",
    )
    add_sweep_arguments(parser, "bench localization")
    options.add_results(
        parser,
        "docs/results/bench_localization_test_realistic.json",
        note="; always written as bench_localization.results.json under --out",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from symloc.bench.localization import (
        WorldResult,
        WorldTask,
        method_order,
        run_world,
        summarize,
        trial_rows,
        world_summary,
    )
    from symloc.bench.localization_results import write_localization_results
    from symloc.bench.provenance import RunClock, command_line, machine
    from symloc.bench.stats import json_safe
    from symloc.bench.sweep import run_sweep
    from symloc.bench.trial import TrialConfig
    from symloc.bench.world_sources import family_refs, file_refs, split_seeds
    from symloc.errors import ConfigurationError
    from symloc.figures.bench import outcome_figure
    from symloc.sim.generator import FAMILIES

    if args.worlds < 1 or args.trials < 1:
        raise ConfigurationError("--worlds and --trials: expected integers >= 1")
    if 0 < args.mapping_reach < options.MIN_MAPPING_REACH:
        raise ConfigurationError(
            f"--mapping-reach: expected 0 (the lap only) or at least "
            f"{options.MIN_MAPPING_REACH} m, got {args.mapping_reach}"
        )
    seeds = args.seeds if args.seeds else split_seeds(args.split, args.worlds)
    if args.world:
        families = [f"file:{p}" for p in args.world]
        refs = file_refs(args.world, seeds)
    else:
        families = args.families or list(FAMILIES)
        refs = family_refs(families, seeds)
    config = TrialConfig(claim_timeout=args.claim_timeout, track_time=args.track_time)
    tasks = [
        WorldTask(
            ref=ref,
            trials=args.trials,
            kinds=tuple(args.kinds),
            regime=args.regime,
            map_source=args.map,
            mapping_reach=args.mapping_reach,
            config=config,
            methods=tuple(args.methods),
        )
        for ref in refs
    ]
    settings = {
        "families": families,
        "split": None if args.seeds else args.split,
        "world_seeds": seeds,
        "worlds": len(tasks),
        "trials_per_world": args.trials,
        "trial_kinds": list(args.kinds),
        "methods": list(args.methods),
        "regime": args.regime,
        "map": args.map,
        "mapping_reach_m": args.mapping_reach,
        "tolerance": config.tolerance.describe(),
        "claim_timeout_s": config.claim_timeout,
        "track_time_s": config.track_time,
        "kidnap_after_s": config.kidnap_after,
        "start_clearance_m": config.clearance,
        "robot_seed": "WorldRef.robot_seed: SeedSequence([crc32(family), world_seed])",
        "trial_seed": "WorldRef.trial_seed: SeedSequence([crc32(family), world_seed, trial index])",
    }
    print("# symloc bench localization")
    for key, value in settings.items():
        print(f"#   {key}: {value}")
    print(f"#   workers: {args.workers}" + (f" on Ray ({args.ray})" if args.ray else ""))
    sys.stdout.flush()
    total = len(tasks) * args.trials
    counts = {"correct": 0, "confident_wrong": 0, "undetermined": 0}
    bar = tqdm(total=total, unit="trial", desc="trials", file=sys.stderr)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    # Each finished world is appended at once, so a sweep stopped after hours keeps its trials.
    partial = out / "bench_localization.partial.jsonl"
    partial.write_text("")

    def on_result(_i: int, w: WorldResult) -> None:
        line = world_summary(w) | {"trials": trial_rows([w])}
        with partial.open("a") as fh:
            fh.write(json.dumps(json_safe(line)) + "\n")
        for tr in w.trials:
            mr = tr.results.get("symloc") or next(iter(tr.results.values()))
            counts[mr.grade.grade] += 1
        bar.update(len(w.trials))
        bar.set_postfix(
            ok=counts["correct"], wrong=counts["confident_wrong"], undet=counts["undetermined"]
        )

    clock = RunClock()
    t0 = time.perf_counter()
    results = run_sweep(run_world, tasks, workers=args.workers, ray=args.ray, on_result=on_result)
    bar.close()
    wall = time.perf_counter() - t0
    rows = trial_rows(results)
    summary = summarize(rows)
    _print_table(method_order(summary))
    doc = {
        "command": "symloc bench localization",
        "settings": settings,
        "summary": summary,
        "worlds": [
            world_summary(w) | {"map_seconds": None, "trial_seconds": None} for w in results
        ],
        "trials": rows,
    }
    path = write_json(out / "bench_localization.json", doc)
    if args.json is not None:
        write_json(args.json, doc)
    timing = {
        "wall_s": wall,
        "workers": args.workers,
        "ray": args.ray,
        "map_s": [w.map_seconds for w in results],
        "trials_s": [w.trial_seconds for w in results],
    }
    write_json(out / "timing.json", timing)
    clock.stop()
    written = [
        write_localization_results(
            target,
            doc,
            command=command_line(getattr(args, "argv", [])),
            commit=clock.revision,
            date=clock.finished or clock.started,
            machine=machine(),
            load=clock.load(),
            workers=args.workers,
            wall_s=wall,
            note=f"Ray {args.ray}" if args.ray else None,
        )
        for target in [out / "bench_localization.results.json", args.results]
        if target is not None
    ]
    fig = outcome_figure(
        summary,
        out / "bench_localization.png",
        title=f"symloc bench localization: {len(tasks)} worlds x {args.trials} trials "
        f"({settings['split'] or 'explicit seeds'}), regime {args.regime}",
    )
    print(f"wrote {path}, {fig}, {out / 'timing.json'} and {', '.join(map(str, written))}")
    print(f"wall time {wall:.0f} s for {total} trials on {args.workers} worker(s)")
    return 0


def _pct(k: int, n: int) -> str:
    return f"{100 * k / n:.1f}" if n else "-"


def _print_table(summary: list[dict[str, Any]]) -> None:
    print()
    head = (
        f"{'family':<18} {'method':<7} {'trials':>6} {'correct %':>9} "
        f"{'conf. wrong % [95% CI]':>24} {'undet. %':>8} {'t claim':>8} {'d claim':>8} "
        f"{'p95 err':>8} {'cov.':>5} {'head ok %':>9} {'head wrong %':>12}"
    )
    print(head)
    print("-" * len(head))
    for r in summary:
        n = r["trials"]
        lo, hi = r["confident_wrong_ci95"]
        cw = f"{_pct(r['confident_wrong'], n)} [{100 * lo:.1f}, {100 * hi:.1f}]"
        t = r["median_time_to_claim_s"]
        d = r["median_distance_to_claim_m"]
        e = r["tracking_error_p95_m"]
        c = r["covariance_coverage"]
        print(
            f"{r['family']:<18} {r['method']:<7} {n:>6} {_pct(r['correct'], n):>9} {cw:>24} "
            f"{_pct(r['undetermined'], n):>8} "
            f"{'-' if math.isnan(t) else f'{t:.1f} s':>8} "
            f"{'-' if math.isnan(d) else f'{d:.2f} m':>8} "
            f"{'-' if math.isnan(e) else f'{100 * e:.1f} cm':>8} "
            f"{'-' if math.isnan(c) else f'{c:.2f}':>5} "
            f"{_pct(r['heading_correct'], n):>9} {_pct(r['heading_wrong'], n):>12}"
        )
    print(
        "(t claim / d claim: median time and distance from the start or the kidnapping to the "
        "first pose published as tracking; p95 err: median over trials of the 95th percentile "
        "of the position error while tracking; cov.: share of claims inside their published "
        "95 % covariance ellipsoid; head ok / head wrong: trials whose first heading (an axis "
        "estimate or a claim) was within 5 deg / with any heading off by more)"
    )
