"""``symloc replay BAG``: run the localizer over a ROS 1 / ROS 2 bag; TUM trajectories + PNG.

Into ``--out DIR``: ``replay.tum`` (the poses the localizer earned, status tracking: what a
robot would act on), ``replay_scans.tum`` (AMCL's best estimate at every scan, earned or not,
carried by odometry from the filter's last update, so evo sees the whole run),
``replay_scans.csv`` (every scan's status, estimate and reason) and
``replay.png``. A run that never earned a pose says why and exits with code 3.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["register"]


def register(subparsers: Any) -> None:
    """Add the ``replay`` sub-command."""
    p: argparse.ArgumentParser = subparsers.add_parser(
        "replay",
        help="run the localizer over a recorded bag (ROS 1 .bag, ROS 2 .db3 / .mcap)",
        description="Run the symloc localizer over a recorded bag with the ROS node's own logic."
        " Writes into --out: replay.tum (tracked poses), replay_scans.tum (AMCL's estimate at"
        " every scan), replay_scans.csv (every scan's status and reason) and replay.png."
        " Exit code 3 when no pose was earned.",
    )
    p.add_argument("bag", type=Path, help="ROS 1 .bag file or ROS 2 bag folder (or its .db3/.mcap)")
    p.add_argument(
        "--map", type=Path, default=None, help="map_server YAML (default: the bag's map topic)"
    )
    p.add_argument("--visual-map", type=Path, default=None, help="visual map database (places.db)")
    p.add_argument(
        "--vocabulary", type=Path, default=None, help="vocabulary the visual map was built with"
    )
    p.add_argument("--params", type=Path, default=None, help="node parameters YAML (nav2 style)")
    p.add_argument("--scan-topic", default=None, help="LaserScan topic (default: the first one)")
    p.add_argument("--odom-topic", default=None, help="Odometry topic (default: the first one)")
    p.add_argument("--image-topic", default=None, help="Image or CompressedImage topic")
    p.add_argument(
        "--truth-topic", default="ground_truth", help="ground-truth Odometry topic, if any"
    )
    options.add_seed(p, overrides="the --params file's seed, else 0")
    p.add_argument(
        "--build-map",
        type=options.output_file,
        default=None,
        metavar="MAP.yaml",
        help="instead of localizing, build the occupancy grid from the bag's scans and odometry"
        " (symloc SLAM) and save it in map_server format",
    )
    p.add_argument(
        "--build-visual-map",
        action="store_true",
        help="mode build_visual_map: places that match nothing are added to --visual-map (the"
        " bag must hold the robot's trip to the centre and its images, as a node run records)",
    )
    options.add_out(p, "replay", what="replay.tum, replay_scans.tum, replay_scans.csv, replay.png")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import dataclasses

    from symloc.io.rosbag import BagTopics
    from symloc.io.tum import write_tum
    from symloc.ros.params import NodeParams
    from symloc.ros.replay import replay_bag

    if args.build_map is not None:
        return _build_map(args)
    params = NodeParams.from_yaml(args.params) if args.params else NodeParams()
    changes: dict[str, Any] = {"map_yaml": ""}
    if args.build_visual_map:
        changes["mode"] = "build_visual_map"
    if args.visual_map is not None:
        changes["visual_map"] = str(args.visual_map)
    if args.vocabulary is not None:
        changes["vocabulary"] = str(args.vocabulary)
    if args.seed_given or args.params is None:
        changes["seed"] = args.seed
    params = dataclasses.replace(params, **changes)
    grid = None
    map_std_xy = None
    map_error_field = None
    if args.map is not None:
        try:
            from symloc.grid.map_io import load_map, read_map_yaml
        except ImportError as err:
            from symloc.errors import ConfigurationError

            raise ConfigurationError("--map: map_server file support is missing") from err
        grid = load_map(args.map)
        meta = read_map_yaml(args.map)
        map_std_xy, map_error_field = meta.map_std_xy, meta.map_error_field
    out = Path(args.out)
    options.refuse_overwriting_inputs(
        {"bag": args.bag, "--map": args.map, "--params": args.params},
        {"--out": out, "--out/replay.tum": out / "replay.tum"},
    )
    print(f"# symloc replay {args.bag}")
    print(f"#   seed: {params.seed}")
    print(f"#   map: {args.map or 'from the bag'}; visual map: {params.visual_map or 'none'}")
    if not params.visual_map:
        print(
            "#   without a visual map a symmetric room cannot be resolved: the localizer can"
            " earn a pose only where the map itself is not symmetric"
        )
    topics = BagTopics(
        scan=args.scan_topic, odom=args.odom_topic, image=args.image_topic, truth=args.truth_topic
    )
    res = replay_bag(
        args.bag,
        params,
        grid=grid,
        map_std_xy=map_std_xy,
        map_error_field=map_error_field,
        topics=topics,
        warn=lambda text: print(f"warning: {text}", file=sys.stderr),
        progress=True,
    )
    if res.grid is None:
        print("symloc: error: no map (give --map or record the map topic)", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    tum = out / "replay.tum"
    tracked = [(p.stamp, p.pose) for p in res.trajectory if p.pose is not None]
    write_tum(tum, tracked)
    scans_tum = out / "replay_scans.tum"
    write_tum(scans_tum, [(p.stamp, p.estimate) for p in res.trajectory if p.estimate is not None])
    scans_csv = out / "replay_scans.csv"
    _write_scans_csv(scans_csv, res.trajectory)
    from symloc.figures.replay import plot_replay

    png = plot_replay(
        out / "replay.png",
        grid=res.grid,
        trajectory=res.trajectory,
        truth=res.truth,
        particles=res.particles,
        title=f"symloc replay of {Path(args.bag).name}",
    )
    counts: dict[str, int] = {}
    for p in res.trajectory:
        counts[p.status] = counts.get(p.status, 0) + 1
    print(f"scans used: {len(res.trajectory)} of {res.scans}  status counts: {counts}")
    print(f"dropped: {res.dropped or 'none'}")
    for note in res.clock_notes:
        print(f"clock: {note}")
    verdict = res.verdict
    print(verdict.text)
    if res.final is not None:
        print(f"final: {res.final.status.value}: {res.final.reason}")
        if res.final.pose is not None and len(res.truth):
            import math

            import numpy as np

            d = res.final.pose - res.truth[-1, 1:]
            print(
                f"final error vs ground truth: {np.hypot(d[0], d[1]):.4f} m,"
                f" {math.degrees(abs(math.remainder(float(d[2]), 2 * math.pi))):.2f} deg"
            )
    for line in res.steps:
        print(f"  step: {line}")
    print(f"wrote {tum} ({len(tracked)} tracked poses of {len(res.trajectory)} scans)")
    print(f"wrote {scans_tum} and {scans_csv} (every scan: estimate and status)")
    print(f"wrote {png}")
    if not verdict.usable:
        print(f"symloc: {verdict.text}", file=sys.stderr)
        return 3
    if not tracked:
        why = (
            "no visual map was given (--visual-map), so a symmetric room stays ambiguous"
            if not params.visual_map
            else "see the status counts and steps above"
        )
        print(
            f"symloc: no pose was earned in {len(res.trajectory)} scans: replay.tum is empty;"
            f" {why}",
            file=sys.stderr,
        )
        return 3
    return 0


def _write_scans_csv(path: Path, trajectory: list[Any]) -> None:
    """One row per scan used: stamp, status, tracked, AMCL's estimate (x, y, theta_deg)."""
    import csv
    import math

    from symloc.files.atomic import atomic_open

    with atomic_open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["stamp", "status", "tracked", "x", "y", "theta_deg", "reason"])
        for p in trajectory:
            e = p.estimate
            xyz = ["", "", ""] if e is None else [f"{e[0]:.6f}", f"{e[1]:.6f}"]
            if e is not None:
                xyz.append(f"{math.degrees(float(e[2])):.4f}")
            w.writerow([f"{p.stamp:.9f}", p.status, int(p.pose is not None), *xyz, p.reason])


def _build_map(args: argparse.Namespace) -> int:
    from symloc.grid.map_io import save_map
    from symloc.io.rosbag import BagTopics
    from symloc.io.tum import write_tum
    from symloc.ros.replay import build_map_from_bag

    options.refuse_overwriting_inputs({"bag": args.bag}, {"--build-map": args.build_map})
    print(f"# symloc replay {args.bag} --build-map {args.build_map}")
    topics = BagTopics(scan=args.scan_topic, odom=args.odom_topic, truth=None)
    built = build_map_from_bag(args.bag, topics=topics)
    res = built.slam
    paired = built.paired
    print(
        f"scans paired with odometry: {len(paired.scans)} of {paired.total}"
        f" (dropped: {paired.dropped or 'none'})"
    )
    for note in paired.clock_notes:
        print(f"clock: {note}")
    path = save_map(res.grid, args.build_map, extra=res.map_metadata())
    stem = Path(args.build_map)
    tum = stem.with_name(stem.name.removesuffix(".yaml") + "_trajectory.tum")
    write_tum(tum, list(zip(built.stamps.tolist(), res.poses, strict=True)))
    print(
        f"map: {res.grid.width} x {res.grid.height} cells at {res.grid.resolution} m;"
        f" {len(res.poses)} scans, {len(res.loop_closures)} loop closures accepted,"
        f" {len(res.rejected_loops)} rejected; result"
        f" {'DOUBTFUL' if res.doubtful else 'consistent'}"
    )
    for w in res.warnings:
        print(f"  warning: {w}")
    print(f"wrote {path} and {tum} (the SLAM poses of the scans, TUM)")
    if res.doubtful:
        print(
            f"symloc: warning: the map in {path} is doubtful (see the warnings above): look at"
            " it before localizing on it",
            file=sys.stderr,
        )
    return 0
