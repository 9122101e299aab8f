"""``symloc map build``: build an occupancy grid by laser SLAM and save it for map_server."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["register"]


def register(subparsers: Any) -> None:
    """Add ``map`` with its ``build`` sub-command."""
    from symloc.bench.slam_runs import ODOMETRY_CHOICES, SIM_WORLDS

    parser: argparse.ArgumentParser = subparsers.add_parser(
        "map", help="build occupancy-grid maps by laser SLAM (map_server YAML + PGM)"
    )
    sub = parser.add_subparsers(dest="map_command", metavar="ACTION")
    sub.required = True
    b = sub.add_parser(
        "build",
        help="SLAM from a simulated exploration run or a CARMEN log; writes map.yaml + map.<write id>.pgm",
        description="Run laser SLAM (correlative scan matching against submaps, GTSAM pose graph "
        "with loop closures) and write the map in map_server format plus a PNG of the map and "
        "the trajectory.",
    )
    src = b.add_mutually_exclusive_group(required=True)
    src.add_argument("--world", choices=sorted(SIM_WORLDS), help="simulated world to explore")
    src.add_argument("--carmen", type=Path, metavar="PATH", help="CARMEN log (.log or .log.gz)")
    options.add_out(b, "map build", what="NAME.yaml, NAME.<write id>.pgm and NAME_trajectory.png")
    b.add_argument(
        "--name", type=options.file_stem, default="map", help="file stem of the map (default: map)"
    )
    options.add_seed(b)
    b.add_argument(
        "--odometry",
        choices=ODOMETRY_CHOICES,
        default="realistic",
        help="odometry: a simulated regime on the true / corrected increments (realistic: "
        "calibrated wheels, heavy: GMapping's filter noise), or the log's own (log)",
    )
    b.add_argument(
        "--max-scans",
        type=options.positive_int,
        default=None,
        metavar="N",
        help="CARMEN: the first N scans only",
    )
    b.add_argument(
        "--laps",
        type=options.laps,
        default=1.3,
        help="simulation: loops around the room (default 1.3)",
    )
    b.add_argument(
        "--resolution",
        type=options.map_resolution,
        default=0.05,
        help="map cell size [m] (default 0.05)",
    )
    b.add_argument(
        "--mode", choices=["trinary", "scale", "raw"], default="trinary", help="map_server mode"
    )
    b.set_defaults(func=_build)


def _build(args: argparse.Namespace) -> int:
    from symloc.bench.slam_runs import run_carmen, run_simulated
    from symloc.errors import ConfigurationError
    from symloc.figures.slam import map_trajectory_figure
    from symloc.geometry import compose, inverse
    from symloc.grid.map_io import read_map_yaml, save_map
    from symloc.sim.odometry_noise import ODOMETRY_REGIMES
    from symloc.slam.slam import SlamParams

    params = SlamParams(map_resolution=args.resolution)
    source = f"world {args.world}" if args.world else f"CARMEN log {args.carmen}"
    regime = ODOMETRY_REGIMES.get(args.odometry)
    odo = regime.describe() if regime is not None else "the log's own"
    print(f"# symloc map build: {source}, seed {args.seed}, odometry {odo}")
    if args.world:
        if regime is None:
            raise ConfigurationError("--odometry log needs a CARMEN log (--carmen)")
        run = run_simulated(
            args.world,
            odometry=regime,
            rng=args.seed,
            params=params,
            laps=args.laps,
        )
        reference = run.reference
    else:
        if not args.carmen.is_file():
            raise ConfigurationError(f"--carmen {args.carmen}: not found; expected a CARMEN log")
        run = run_carmen(
            args.carmen,
            odometry=args.odometry,
            rng=args.seed,
            params=params,
            max_scans=args.max_scans,
        )
        reference = compose(inverse(run.ate.alignment), run.reference)
    s = run.summary()
    out = Path(args.out)
    yaml_path = save_map(
        run.result.grid, out / args.name, mode=args.mode, extra=run.result.map_metadata()
    )
    png = map_trajectory_figure(
        run.result.grid,
        run.result.poses,
        out / f"{args.name}_trajectory.png",
        reference=reference,
        odometry=run.odometry if args.world else None,
        loop_nodes=[i for _, i in run.result.loop_closures],
        title=f"{run.name}: ATE {s['ate_rmse_m']:.3f} m, {s['loop_closures']} loop closures",
    )
    print(
        f"scans {s['scans']}  ATE RMSE {s['ate_rmse_m']:.3f} m (odometry {s['ate_odometry_rmse_m']:.3f} m)"
        f"  RPE {s['rpe_trans_rmse_m']:.3f} m / {s['rpe_rot_rmse_deg']:.2f} deg"
        f"  loop closures {s['loop_closures']}  speed x{s['realtime_factor_cpu']:.1f} (CPU)"
        if s["realtime_factor_cpu"] == s["realtime_factor_cpu"]
        else f"  loop closures {s['loop_closures']}  speed: no usable timestamps"
    )
    if "map_agreement" in s:
        print(
            f"map agreement with the rasterised world: {s['map_agreement']:.3f} exact,"
            f" {s['map_agreement_tol1']:.3f} within one cell"
        )
    res = run.result
    print(
        f"loop closures accepted {len(res.loop_closures)}, rejected {len(res.rejected_loops)};"
        f" result {'DOUBTFUL' if res.doubtful else 'consistent'}"
    )
    for w in res.warnings:
        print(f"  warning: {w}")
    print(f"wrote {yaml_path}, {read_map_yaml(yaml_path).image}, {png}")
    return 0
