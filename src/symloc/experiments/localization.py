"""``symloc experiment localization``: kidnapped-robot trials per room, plain AMCL vs symloc."""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path
from typing import Any

from symloc.cli import options
from symloc.experiments._common import add_common_arguments, print_config, write_json

__all__ = ["ROOMS", "register", "run"]

#: (room, textured lab) pairs of the issue: seven rooms in a textured lab, the square untextured,
#: and a true hallway (40 m x 2 m, its ends beyond the lidar's range; the built-in "hallway" is
#: only 6.3 m long, so the lidar sees all of it and the judge calls it a rectangle).
ROOMS = (
    ("triangle", True),
    ("square", True),
    ("pentagon", True),
    ("hexagon", True),
    ("circle", True),
    ("rectangle", True),
    ("hallway", True),
    ("hallway_40m", True),
    ("square", False),
)
#: ``--rooms`` names of :data:`ROOMS`.
ROOM_KEYS = tuple(r if textured else f"{r}-untextured" for r, textured in ROOMS)


def register(subparsers: Any) -> None:
    """Add ``localization`` to ``symloc experiment``."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "localization",
        help="kidnapped-robot trials per room: plain AMCL vs symloc (correct / confident wrong "
        "/ undetermined)",
    )
    add_common_arguments(parser, "localization")
    options.add_trials(parser, default=100, what="trials per room")
    options.add_rooms(
        parser, rooms=ROOM_KEYS, help="rooms ('square-untextured': the square in a plain lab)"
    )
    parser.add_argument(
        "--amcl-duration",
        type=options.sim_seconds,
        default=45.0,
        help="plain AMCL drive time [s] (default 45, as amcl-symmetric)",
    )
    options.add_lidar(parser)
    parser.add_argument(
        "--map",
        choices=("slam", "raster"),
        default="slam",
        help="occupancy grid and visual-map poses from SLAM (default) or from ground truth",
    )
    parser.set_defaults(func=run)


def _selected(names: list[str]) -> list[tuple[str, bool]]:
    out = []
    for n in options.room_names(names, ROOM_KEYS):
        if n.endswith("-untextured"):
            out.append((n.removesuffix("-untextured"), False))
        else:
            out.append((n, True))
    return out


def run(args: argparse.Namespace) -> int:
    from symloc.bench.room_trials import run_room_trials
    from symloc.bench.scenario import MAP_SOURCE
    from symloc.figures.demo import localization_figure
    from symloc.sim.lidar import PRESETS

    rooms = _selected(args.rooms)
    print_config(
        "localization",
        {
            "seed": args.seed,
            "trials per room": args.trials,
            "rooms": ", ".join(f"{r} ({'textured' if t else 'untextured'} lab)" for r, t in rooms),
            "lidar": args.lidar,
            "correct": "claimed pose within 0.1 m and 5 deg of the truth",
            "plain AMCL": "nav2 defaults (2000/500 particles, likelihood field), alpha1..4 "
            "matched to the robot's odometry noise; global start; the robot drives a seeded "
            f"collision-free random path at 0.3 m/s for {args.amcl_duration:g} s",
            "confident (both methods' AMCL)": _confidence_summary(),
            "symloc": "claims a pose only with status tracking",
            "maps": "symloc.slam.run_slam over the mapping trip (image poses from SLAM)"
            if args.map == "slam"
            else MAP_SOURCE,
        },
    )
    rows: list[dict[str, Any]] = []
    notes: list[str] = []
    with tempfile.TemporaryDirectory(prefix="symloc-loc-") as tmp:
        for i, (room, textured) in enumerate(rooms):
            res = run_room_trials(
                room,
                textured=textured,
                trials=args.trials,
                rng=args.seed + 1000 * i,
                workdir=Path(tmp),
                amcl_duration=args.amcl_duration,
                preset=PRESETS[args.lidar],
                map_source=args.map,
            )
            rows.extend(res.rows())
            if res.judge_errors:
                notes.append(f"{room}: the symmetry judge raised {res.judge_errors} times")
            notes.append(f"{room} ({res.lab}): {res.map_note}")
            if res.collisions or res.amcl_collisions:
                notes.append(
                    f"{room}: refused (colliding) motions: symloc {res.collisions}, "
                    f"plain AMCL {res.amcl_collisions}"
                )
            _print_room(res.rows())
    print()
    print(
        f"{'room':<10} {'lab':<11} {'method':<7} {'correct':>8} {'conf.wrong':>10} "
        f"{'undet.':>7} {'med. time':>9} {'med. dist':>9} {'est.@true':>9} {'est.@copy':>9}"
    )
    for r in rows:
        n = max(r["trials"], 1)
        t = r["median_time_s"]
        d = r["median_distance_m"]
        print(
            f"{r['room']:<10} {r['lab']:<11} {r['method']:<7} {100 * r['correct'] / n:>7.0f}% "
            f"{100 * r['confident_wrong'] / n:>9.0f}% {100 * r['undetermined'] / n:>6.0f}% "
            f"{'-' if math.isnan(t) else f'{t:.1f} s':>9} {'-' if math.isnan(d) else f'{d:.2f} m':>9}"
            f" {100 * r['estimate_near_true_pose'] / n:>8.0f}%"
            f" {100 * r['estimate_near_symmetric_copy'] / n:>8.0f}%"
        )
    print(
        "(est.@true / est.@copy: the final estimate, claimed or not, lies within 0.3 m and 10 deg "
        "of the true pose / of a wrong symmetric copy; for plain AMCL that estimate is the pose "
        "nav2 publishes on /amcl_pose, confident or not)"
    )
    for note in notes:
        print(f"note: {note}")
    path = localization_figure(rows, args.out / "localization.png")
    print(f"wrote {path}")
    write_json(
        args.json,
        {
            "seed": args.seed,
            "trials": args.trials,
            "lidar": args.lidar,
            "map": args.map,
            "amcl_duration_s": args.amcl_duration,
            "rooms": rows,
        },
    )
    return 0


def _print_room(rows: list[dict[str, Any]]) -> None:
    for r in rows:
        print(
            f"  {r['room']} ({r['lab']}) {r['method']}: {r['correct']}/{r['trials']} correct, "
            f"{r['confident_wrong']} confident wrong, {r['undetermined']} undetermined"
        )
        for reason, count in r["reasons"].items():
            print(f"      {count} x {reason}")


def _confidence_summary() -> str:
    """The confidence definition in force, read from ``ConfidenceConfig``'s defaults."""
    from symloc.mcl.confidence import ConfidenceConfig

    c = ConfidenceConfig()
    return (
        f"symloc.mcl.confidence: heaviest cluster >= {c.min_weight_share:g} of the weight, its "
        f"std <= {c.max_xy_std:g} m and {math.degrees(c.max_theta_std):g} deg, >= "
        f"{100 * c.min_scan_consistency:g} % of beams within {c.consistency_sigmas:g} sigma_hit "
        f"of the map, for {c.hold_updates} updates; plain AMCL graded without the rival search "
        "(what nav2 can know), symloc with it"
    )
