"""``symloc experiment slam``: laser SLAM in the simulator and on the three CARMEN logs.

Simulator rows (:data:`symloc.bench.slam_runs.SIM_WORLDS`): the paper's 3 m x 3 m square of boards
inside the lab, an L-shaped room and a hallway; the simulated robot drives ``--laps`` loops
0.5 m from the walls with the paper's 15 m scanner (360 beams, sigma 10 mm) and the odometry
regime ``--odometry`` on the increments between scans; reported: ATE RMSE against the ground truth and the fraction of map cells
that agree with the rasterised world (exactly and within one cell).

CARMEN rows ("corrected" logs, default intel and aces): odometry is made by applying the
regime ``--odometry`` (:mod:`symloc.sim.odometry_noise`: ``realistic`` or ``heavy``, seeded) to
the increments of the corrected poses, or is the log's own (``log``, where it has any);
reported: ATE RMSE (SE(2) Umeyama alignment) and RPE (consecutive scans) against the corrected
poses, evo's definitions; loop closures; processing speed as data duration / CPU time and /
wall-clock time. Targets: ATE < 0.10 m on intel and aces, >= 10x real time.

Seeds: each world and log draws its noise from
:func:`symloc.bench.slam_runs.odometry_seed` (its name, ``--seed``), as ``symloc map build``
and ``symloc bench slam`` do: a row is the same whether run alone, with the others or by those
commands.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path
from typing import Any

from symloc.bench.shared_data import CARMEN_LOGS, carmen_log_paths
from symloc.cli import options
from symloc.errors import ConfigurationError
from symloc.experiments._common import (
    add_common_arguments,
    print_config,
    write_json,
)

__all__ = ["CARMEN_LOGS", "DEFAULT_LOGS", "register", "run"]

#: Logs run when ``--logs`` is not given (if the data is on this machine).
DEFAULT_LOGS = ("intel", "aces")


def register(subparsers: Any) -> None:
    """Add ``slam`` to ``symloc experiment``."""
    from symloc.bench.slam_runs import ODOMETRY_CHOICES, SIM_WORLDS

    parser: argparse.ArgumentParser = subparsers.add_parser(
        "slam", help="laser SLAM: simulated rooms and the CARMEN logs (ATE, RPE, loops, speed)"
    )
    add_common_arguments(parser, "slam")
    options.add_results(parser, "docs/results/experiment_slam.json")
    parser.add_argument(
        "--worlds", nargs="*", default=list(SIM_WORLDS), help="simulated worlds (none: skip)"
    )
    parser.add_argument(
        "--logs",
        nargs="*",
        default=None,
        help="CARMEN logs (intel aces freiburg-079; freiburg-079 is long); default intel aces"
        " when the logs are found (else skipped with a warning); logs named here must exist",
    )
    parser.add_argument("--data", type=Path, default=None, help="folder with the CARMEN logs")
    parser.add_argument(
        "--odometry",
        choices=ODOMETRY_CHOICES,
        default="realistic",
        help="odometry regime (symloc.sim.odometry_noise) or the log's own odometry",
    )
    parser.add_argument(
        "--max-scans", type=options.positive_int, default=None, help="use only the first N scans"
    )
    parser.add_argument("--laps", type=options.laps, default=1.3, help="loops of the simulated run")
    parser.add_argument(
        "--loop-every",
        type=options.positive_int,
        default=None,
        help="search loop closures every N graph nodes (default: SlamParams, every node, sampled)",
    )
    parser.add_argument(
        "--match-filtered",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="also scan-match the scans the motion filter drops (default: SlamParams, off)",
    )
    parser.add_argument(
        "--loop-resample",
        type=options.nonnegative_float,
        default=None,
        help="travel [m] before a submap is searched for loops again (default: SlamParams)",
    )
    parser.add_argument(
        "--loop-constrained",
        type=options.nonnegative_float,
        default=None,
        help="travel [m] before a submap with a found loop is searched again (default: SlamParams)",
    )
    parser.set_defaults(func=run)


def _row(s: dict[str, Any]) -> str:
    agree = (
        f"  map agree {s['map_agreement']:.3f} (+-1 cell {s['map_agreement_tol1']:.3f})"
        if "map_agreement" in s
        else ""
    )
    rtf = s["realtime_factor_cpu"]
    speed = (
        f"  speed x{rtf:.1f} CPU, x{s['realtime_factor_wall']:.1f} wall"
        if rtf == rtf
        else "  speed: no usable timestamps"
    )
    return (
        f"{s['name']:<14} scans {s['scans']:>5}  ATE {s['ate_rmse_m']:.3f} m"
        f" (odom {s['ate_odometry_rmse_m']:.3f})  RPE {s['rpe_trans_rmse_m']:.3f} m"
        f" {s['rpe_rot_rmse_deg']:.2f} deg  loops {s['loop_closures']:>4}"
        f" (rejected {s['loops_rejected']})"
        f"{speed}{agree}"
    )


def _print_warnings(s: dict[str, Any]) -> None:
    for w in s.get("warnings", []):
        print(f"{'':<14} doubtful: {w}")


def _requested_logs(args: argparse.Namespace) -> dict[str, Path]:
    """The CARMEN logs to run: those named with ``--logs`` must all exist (else a
    ConfigurationError before any work); the default ones are skipped, with a warning, when the
    data is not on this machine."""
    if args.logs is not None:
        return carmen_log_paths(args.logs, args.data) if args.logs else {}
    try:
        return carmen_log_paths(DEFAULT_LOGS, args.data)
    except ConfigurationError as err:
        if args.data is not None:
            raise
        print(f"warning: skipping the default logs: {err}", file=sys.stderr)
        return {}


def run(args: argparse.Namespace) -> int:
    """Run every requested world and log; print a table, write JSON and figures."""
    from symloc.bench.slam_runs import SIM_WORLDS, run_carmen, run_simulated
    from symloc.figures.slam import map_trajectory_figure, slam_summary_figure
    from symloc.geometry import compose, inverse
    from symloc.sim.odometry_noise import ODOMETRY_REGIMES
    from symloc.slam.slam import SlamParams

    regime = ODOMETRY_REGIMES.get(args.odometry)
    worlds = list(args.worlds) if regime is not None else []
    if regime is None and args.worlds:
        print(
            f"warning: --odometry log needs a log; skipping the simulated worlds"
            f" {' '.join(args.worlds)}",
            file=sys.stderr,
        )
    unknown = [w for w in worlds if w not in SIM_WORLDS]
    if unknown:  # before any world runs
        raise ConfigurationError(
            f"--worlds {' '.join(unknown)}: world: expected one of {', '.join(SIM_WORLDS)}"
        )
    logs = _requested_logs(args)
    if not worlds and not logs:
        raise ConfigurationError(
            "nothing to run: no simulated world (--worlds; --odometry log needs a log) and no"
            " CARMEN log (--logs)"
        )
    params = SlamParams()
    if args.loop_every is not None:
        params = dataclasses.replace(params, loop_every=args.loop_every)
    if args.match_filtered is not None:
        params = dataclasses.replace(params, match_filtered_scans=args.match_filtered)
    if args.loop_resample is not None:
        params = dataclasses.replace(params, loop_resample_distance=args.loop_resample)
    if args.loop_constrained is not None:
        params = dataclasses.replace(params, loop_constrained_distance=args.loop_constrained)
    from symloc.bench.provenance import RunClock
    from symloc.bench.results_file import write_run_results

    config = {
        "seed": args.seed,
        "odometry_seed": "SeedSequence([seed, crc32(name)]), as map build and bench slam",
        "worlds": worlds,
        "logs": list(logs),
        "odometry": regime.describe() if regime is not None else "the log's own",
        "max_scans": args.max_scans,
        "laps": args.laps,
        "loop_every": params.loop_every,
        "match_filtered_scans": params.match_filtered_scans,
        "loop_resample_distance": params.loop_resample_distance,
        "loop_constrained_distance": params.loop_constrained_distance,
    }
    print_config("slam", config)
    clock = RunClock()
    rows: list[dict[str, Any]] = []
    out = Path(args.out)
    for world in worlds:
        assert regime is not None
        r = run_simulated(
            world,
            odometry=regime,
            rng=args.seed,
            laps=args.laps,
            params=params,
        )
        s = r.summary()
        rows.append(s)
        print(_row(s))
        _print_warnings(s)
        sys.stdout.flush()
        map_trajectory_figure(
            r.result.grid,
            r.result.poses,
            out / f"slam_{world}.png",
            reference=r.reference,
            odometry=r.odometry,
            loop_nodes=[i for _, i in r.result.loop_closures],
            title=f"{world}: ATE {s['ate_rmse_m']:.3f} m",
        )
    for name, path in logs.items():
        r = run_carmen(
            path,
            odometry=args.odometry,
            rng=args.seed,
            max_scans=args.max_scans,
            params=params,
        )
        s = r.summary()
        rows.append(s)
        print(_row(s))
        _print_warnings(s)
        sys.stdout.flush()
        # the reference in the SLAM map frame (inverse of the ATE alignment)
        aligned_ref = compose(inverse(r.ate.alignment), r.reference)
        map_trajectory_figure(
            r.result.grid,
            r.result.poses,
            out / f"slam_{name}.png",
            reference=aligned_ref,
            loop_nodes=[i for _, i in r.result.loop_closures],
            title=f"{name}: ATE {s['ate_rmse_m']:.3f} m, {s['loop_closures']} loops",
        )
    if rows:
        fig = slam_summary_figure(rows, out / "slam_summary.png")
        print(f"wrote {fig}")
    write_json(args.json, {"seed": args.seed, "odometry": args.odometry, "runs": rows})
    if args.results is not None:
        written = write_run_results(
            args.results,
            argv=getattr(args, "argv", []),
            clock=clock,
            settings=config,
            figures={"runs": rows},
            workers=1,
        )
        print(f"wrote {written}")
    return 0
