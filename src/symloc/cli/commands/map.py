"""``symloc map build``: build an occupancy grid by laser SLAM and save it for map_server.

Sources: a simulated world (``--world``), a CARMEN log (``--carmen``) or a robot's own ROS bag
(``--bag``: scans, odometry on a topic or ``/tf``, and camera images when it has them, which
become the visual map's keyframes; :mod:`symloc.ros.bag_mapping`).
"""

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
        help="SLAM from a simulated exploration run, a CARMEN log or a ROS bag; writes"
        " map.yaml + map.<write id>.pgm (and, from a bag with a camera, the visual map)",
        description="Run laser SLAM (correlative scan matching against submaps, GTSAM pose graph "
        "with loop closures) and write the map in map_server format plus a PNG of the map and "
        "the trajectory. From a ROS bag (--bag) with camera images it also writes the visual "
        "map (keyframes with their SLAM poses) that `symloc replay --visual-map` and the ROS "
        "node's visual_map parameter take.",
    )
    src = b.add_mutually_exclusive_group(required=True)
    src.add_argument("--world", choices=sorted(SIM_WORLDS), help="simulated world to explore")
    src.add_argument("--carmen", type=Path, metavar="PATH", help="CARMEN log (.log or .log.gz)")
    src.add_argument(
        "--bag",
        type=Path,
        metavar="BAG",
        help="ROS 1 .bag or ROS 2 bag folder with LaserScan, odometry (nav_msgs/Odometry or"
        " odom -> base on /tf) and optionally camera images",
    )
    options.add_out(
        b,
        "map build",
        what="NAME.yaml, NAME.<write id>.pgm and NAME_trajectory.png; from a bag also"
        " NAME_trajectory.tum and NAME_visual.db",
    )
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
    g = b.add_argument_group("bag (--bag)")
    g.add_argument("--scan-topic", default=None, help="LaserScan topic (default: the first one)")
    g.add_argument("--odom-topic", default=None, help="Odometry topic (default: the first one)")
    g.add_argument(
        "--image-topic",
        default=None,
        help="Image or CompressedImage topic (default: /camera/image_raw if present, else the"
        " first one)",
    )
    g.add_argument(
        "--truth-topic",
        default="ground_truth",
        help="ground-truth Odometry topic, if any (only to print the ATE; default ground_truth)",
    )
    g.add_argument(
        "--odom-source",
        choices=["auto", "topic", "tf"],
        default="auto",
        help="odometry from the Odometry topic or from /tf (auto: the topic if the bag has one)",
    )
    g.add_argument("--odom-frame", default="odom", help="odometry frame on /tf (default odom)")
    g.add_argument(
        "--base-frame",
        default="",
        help="robot base frame on /tf (default: the frame the odometry frame's transforms lead to)",
    )
    g.add_argument(
        "--vocabulary",
        type=Path,
        default=None,
        help="vocabulary for the keyframes' BoW vectors (default: the shipped one; the node"
        " must be given the same)",
    )
    g.add_argument(
        "--no-visual-map",
        action="store_true",
        help="do not record keyframes even if the bag has camera images",
    )
    b.set_defaults(func=_build)


def _build_from_bag(args: argparse.Namespace) -> int:
    """``map build --bag``: the mapping stage from a recording (module docstring)."""
    import sys

    import numpy as np

    from symloc.bench.slam_metrics import ate
    from symloc.figures.slam import map_trajectory_figure
    from symloc.geometry import compose, inverse
    from symloc.grid.map_io import read_map_yaml
    from symloc.io.rosbag import BagTopics
    from symloc.ros.bag_mapping import BagMappingSettings, map_from_bag, save_bag_mapping
    from symloc.slam.slam import SlamParams
    from symloc.vision.vocabulary import Vocabulary

    out = Path(args.out)
    options.refuse_overwriting_inputs(
        {"--bag": args.bag, "--vocabulary": args.vocabulary},
        {"--out": out, "--out/NAME.yaml": out / f"{args.name}.yaml"},
    )
    out.mkdir(parents=True, exist_ok=True)  # checked while parsing (options.output_folder)
    vocab = Vocabulary.load(args.vocabulary) if args.vocabulary is not None else None
    print(f"# symloc map build --bag {args.bag}, seed {args.seed}")
    topics = BagTopics(
        scan=args.scan_topic,
        odom=args.odom_topic,
        image=args.image_topic,
        truth=args.truth_topic or None,
    )
    settings = BagMappingSettings(
        visual_map=not args.no_visual_map,
        odom_source=args.odom_source,
        odom_frame=args.odom_frame,
        base_frame=args.base_frame,
    )
    built = map_from_bag(
        args.bag,
        topics=topics,
        slam_params=SlamParams(map_resolution=args.resolution),
        settings=settings,
        vocabulary=vocab,
        progress=True,
    )
    files = save_bag_mapping(built, out, args.name, mode=args.mode, vocabulary_file=args.vocabulary)
    res, paired = built.slam, built.paired
    print(
        f"scans: {len(paired.scans)} of {paired.total} paired with odometry from"
        f" {paired.source} (dropped: {paired.dropped or 'none'})"
    )
    if np.any(paired.mount):
        print(
            f"laser mount from /tf_static: {paired.laser_frame} at"
            f" {np.round(paired.mount, 3).tolist()} (x m, y m, yaw rad) on the base"
        )
    for note in paired.clock_notes:
        print(f"clock: {note}")
    print(
        f"map: {res.grid.width} x {res.grid.height} cells at {res.grid.resolution} m;"
        f" {int(res.node_scans.size)} nodes, loop closures accepted {len(res.loop_closures)},"
        f" rejected {len(res.rejected_loops)}; result {'DOUBTFUL' if res.doubtful else 'consistent'}"
    )
    _print_doubts(res)
    ate_text = ""
    reference = None
    ok = np.all(np.isfinite(built.truth), axis=1) if built.truth.size else np.zeros(0, bool)
    if ok.sum() >= 3:
        a = ate(built.truth[ok], built.poses[ok])
        reference = np.asarray(compose(inverse(a.alignment), built.truth[ok]))
        ate_text = f", ATE {a.rmse:.3f} m"
        print(
            f"ATE against {args.truth_topic}: RMSE {a.rmse:.3f} m over {int(ok.sum())} scans"
            " (after the best rigid alignment)"
        )
    else:
        print(f"ATE: no ground truth ({args.truth_topic or 'no truth topic'} not in the bag)")
    if not built.image_topic:
        why = "--no-visual-map" if args.no_visual_map else "the bag has no camera images"
        print(f"visual map: none ({why}); a symmetric room will stay ambiguous")
    else:
        img_dropped = {k: v for k, v in built.dropped.items() if k.startswith("image")}
        print(
            f"visual map: {len(built.keyframes)} keyframes from {built.images} images on"
            f" {built.image_topic} ({built.images_looked_at} looked at"
            f"{f'; dropped: {img_dropped}' if img_dropped else ''})"
        )
    png = map_trajectory_figure(
        res.grid,
        built.poses,
        out / f"{args.name}_trajectory.png",
        reference=reference,
        loop_nodes=[i for _, i in res.loop_closures],
        keyframes=built.keyframe_poses if built.keyframes else None,
        title=f"{Path(args.bag).name}: {len(built.poses)} scans{ate_text},"
        f" {len(built.keyframes)} keyframes",
    )
    written = [str(files.map_yaml), str(read_map_yaml(files.map_yaml).image)]
    written += [str(files.trajectory), str(png)]
    if files.visual_map is not None:
        written.append(str(files.visual_map))
    print(f"wrote {', '.join(written)}")
    if files.visual_map is not None:
        vocab_arg = f" --vocabulary {args.vocabulary}" if args.vocabulary else ""
        print(
            f"next: symloc replay BAG --map {files.map_yaml} --visual-map {files.visual_map}"
            f"{vocab_arg}"
        )
    if res.doubtful:
        print(
            f"symloc: warning: the map in {files.map_yaml} is doubtful (see the warnings above):"
            " look at it before localizing on it",
            file=sys.stderr,
        )
    return 0


def _build(args: argparse.Namespace) -> int:
    if args.bag is not None:
        return _build_from_bag(args)
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
    print(
        f"# symloc map build: {source}, seed {args.seed} (noise stream SeedSequence([seed, "
        f"crc32(name)]), as bench slam and experiment slam), odometry {odo}"
    )
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
    speed = s["realtime_factor_cpu"]
    print(
        f"scans {s['scans']}  ATE RMSE {s['ate_rmse_m']:.3f} m (odometry {s['ate_odometry_rmse_m']:.3f} m)"
        f"  RPE {s['rpe_trans_rmse_m']:.3f} m / {s['rpe_rot_rmse_deg']:.2f} deg"
        f"  loop closures {s['loop_closures']}  "
        + (f"speed x{speed:.1f} (CPU)" if speed == speed else "speed: no usable timestamps")
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
    _print_doubts(res)
    print(f"wrote {yaml_path}, {read_map_yaml(yaml_path).image}, {png}")
    return 0


#: What a doubtful SLAM result means and what to do about it (printed after its warnings).
DOUBTFUL_HELP = (
    "  DOUBTFUL: SLAM saw signs that the map may be wrong somewhere (the warnings above:\n"
    "    scans that left a direction unconstrained or matched too poorly, matches the\n"
    "    odometry disagreed with, loop closures missing or rejected). What to do: look at\n"
    "    the trajectory figure (walls drawn twice or bent show where); record that part again\n"
    "    more slowly, returning to where you started so that the loop can close; check the\n"
    "    odometry source and the laser mount. The claim gate withholds poses by the map's own\n"
    "    error (below), which sees walls that disagree with the scans, and by its error\n"
    "    place by place from the pose graph, which sees a drift only odometry measured."
)


def _print_doubts(res: Any) -> None:
    """What may be wrong with a SLAM result: its warnings and the map's own error."""
    import numpy as np

    for w in res.warnings:
        print(f"  warning: {w}")
    if res.doubtful:
        print(DOUBTFUL_HELP)
    field = res.map_error_field
    if field is not None:
        worst = int(field.major_std.argmax())
        print(
            f"map's error place by place: std median {100 * float(np.median(field.major_std)):.1f}"
            f" cm, worst {100 * field.major_std[worst]:.1f} cm near"
            f" ({field.xy[worst, 0]:.1f}, {field.xy[worst, 1]:.1f}) m over {field.xy.shape[0]}"
            " places, the pose graph's marginals (symloc_slam.map_error.field in the YAML; the"
            " claim gate reads it)"
        )
    me = res.map_error
    if me is None:
        print("map's own error: not estimated (too few usable scans, or a map too large)")
        return
    print(
        f"map's own error: std {100 * me.std_xy:.1f} cm, p95 {100 * me.p95_xy:.1f} cm over"
        f" {me.nodes} nodes, its node scans aligned again to it (symloc_slam.map_error in the"
        " YAML; the claim gate reads it)"
    )
