"""``symloc experiment table2``: the paper's Table 2 (Algorithm 2, share within 5/10/15 mm)."""

from __future__ import annotations

import argparse
from typing import Any

from symloc.cli import options
from symloc.experiments._common import (
    add_common_arguments,
    print_config,
    write_json,
)

__all__ = ["register", "run"]

PAPER = {"5": 0.86, "10": 0.94, "15": 1.00}


def register(subparsers: Any) -> None:
    """Add ``table2`` to ``symloc experiment``."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "table2",
        help="Algorithm 2: share of runs ending within 5/10/15 mm of the centre (paper Table 2)",
    )
    add_common_arguments(parser, "table2")
    parser.add_argument(
        "--positions",
        type=options.count,
        default=50,
        help="start positions, an integer >= 1 (default 50)",
    )
    parser.add_argument(
        "--side", type=options.room_side, default=3.0, help="square side [m] (paper: 3)"
    )
    options.add_lidars(parser, help="simulated lidars (the README's table: rplidar_a2 lds01)")
    options.add_results(parser, "docs/results/table2.json")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symloc.bench.provenance import RunClock
    from symloc.bench.results_file import write_run_results
    from symloc.bench.table2 import run_table2
    from symloc.sim.lidar import PRESETS

    names = options.lidar_names(args.lidar)
    presets = [PRESETS[n] for n in names]
    config = {
        "seed": args.seed,
        "positions": args.positions,
        "room": f"square {args.side:g} m x {args.side:g} m inside a textured lab",
        "presets": ", ".join(names),
        "robot": "DiffDriveRobot (radius 0.177 m, default odometry noise)",
    }
    print_config("table2", config)
    clock = RunClock()
    results = run_table2(presets, positions=args.positions, side=args.side, rng=args.seed)
    print()
    print(
        f"{'sensor':<12} {'R=5 mm':>8} {'R=10 mm':>8} {'R=15 mm':>8} {'median':>9} "
        f"{'max':>8} {'heading':>8} {'done':>6} {'hits':>5}"
    )
    print(f"{'paper':<12} {'86 %':>8} {'94 %':>8} {'100 %':>8}")
    for res in results:
        d: dict[str, Any] = res.to_dict()
        sh = d["shares"]
        print(
            f"{res.preset:<12} {100 * sh['5']:>6.0f} % {100 * sh['10']:>6.0f} % "
            f"{100 * sh['15']:>6.0f} % {d['error_mm_median']:>6.1f} mm {d['error_mm_max']:>5.1f} mm "
            f"{d['heading_error_deg_median']:>6.2f}° {d['finished']:>3}/{d['trials']:<3}"
            f"{d['collisions']:>4}"
        )
    print(
        "(median/max: final distance to the true centre; heading: median error to the "
        "nearest wall middle; hits: refused motions into obstacles)"
    )
    from symloc.figures.demo import table2_figure

    path = table2_figure(results, args.out / "table2.png")
    print(f"wrote {path}")
    write_json(
        args.json, {"seed": args.seed, "paper": PAPER, "results": [r.to_dict() for r in results]}
    )
    if args.results is not None:
        rows = [{k: v for k, v in r.to_dict().items() if k != "errors_mm"} for r in results]
        written = write_run_results(
            args.results,
            argv=getattr(args, "argv", []),
            clock=clock,
            settings=config,
            figures={"paper": PAPER, "results": rows},
            workers=1,
        )
        print(f"wrote {written}")
    return 0
