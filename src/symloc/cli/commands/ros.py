"""``symloc ros node --params params.yaml``: the ROS 2 node (needs ``pip install '.[ros]'`` in symloc's checkout)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["register"]


def register(subparsers: Any) -> None:
    """Add the ``ros`` sub-command group."""
    from symloc.sim.odometry_noise import ODOMETRY_REGIMES

    p: argparse.ArgumentParser = subparsers.add_parser(
        "ros", help="ROS 2 integration (rclpy node)", description="ROS 2 integration."
    )
    sub = p.add_subparsers(dest="ros_command", metavar="COMMAND")
    sub.required = True
    node = sub.add_parser(
        "node",
        help="run the symloc localization node (nav2_amcl's drop-in: lifecycle node 'amcl')",
        description="Run the symloc node, a lifecycle node named amcl that takes nav2_amcl's"
        " place: subscribes scan, map, /tf, /tf_static (or odom), camera, initialpose;"
        " publishes amcl_pose, particle_cloud, map -> odom on /tf, symloc/status,"
        " symloc/candidates, symloc/capture_request (symloc/goal with publish_goals); services"
        " reinitialize_global_localization, request_nomotion_update, set_initial_pose."
        " nav2's lifecycle manager configures and activates it (or --autostart). Arguments"
        " after --ros-args (last) go to rclpy (e.g. --ros-args --params-file nav2_params.yaml"
        " -r scan:=/front/scan -r __ns:=/robot1). Run `symloc ros setup` once first.",
    )
    node.add_argument(
        "--params",
        type=Path,
        default=None,
        help="parameters YAML (nav2's amcl block or symloc's symloc block) giving the"
        " defaults; --ros-args --params-file overrides them",
    )
    node.add_argument(
        "--node-name", default="amcl", help="node name (default amcl, as nav2 expects)"
    )
    node.add_argument(
        "--autostart",
        action="store_true",
        help="configure and activate at start-up (no lifecycle manager)",
    )
    node.add_argument(
        "--ros-args",
        dest="ros_args",
        nargs=argparse.REMAINDER,
        default=None,
        help="everything after it goes to rclpy, as in ros2 run (give it last)",
    )
    node.set_defaults(func=_run_node)
    setup = sub.add_parser(
        "setup",
        help="build tf2_msgs, nav2_msgs (amcl's subset) and bond into this environment",
        description="Build the ROS 2 interface packages the node needs and PyPI lacks"
        " (tf2_msgs; nav2_msgs' ParticleCloud, Particle, SetInitialPose; bond's Status) from"
        " the definitions shipped with symloc, with the ROS generator wheels of"
        " symloc[ros], cmake and a C/C++ compiler, into the active Python environment."
        " Idempotent: what is already there is left alone.",
    )
    setup.add_argument("--force", action="store_true", help="rebuild what symloc built before")
    setup.add_argument(
        "--packages",
        nargs="+",
        choices=("tf2_msgs", "nav2_msgs", "bond"),
        default=None,
        help="build only these (default: all three)",
    )
    setup.add_argument(
        "--keep-build",
        type=options.output_folder,
        default=None,
        help="build in this folder and keep it (logs)",
    )
    setup.set_defaults(func=_setup)
    conv = sub.add_parser(
        "carmen-to-bag",
        help="convert a CARMEN laser log to a ROS bag (scan, odom, ground_truth, initialpose)",
        description="Write the log's scans, odometry and corrected poses as a bag named after the"
        " log inside the output folder: DIR/<log name> (a ROS 2 bag folder) or"
        " DIR/<log name>.bag (ROS 1).",
    )
    conv.add_argument("log", type=Path, help="CARMEN log (.log or .log.gz)")
    options.add_out(conv, "ros carmen-to-bag", what="the bag")
    conv.add_argument(
        "--format",
        choices=("ros2", "mcap", "ros1"),
        default="ros2",
        help="ros2 (sqlite3 .db3, default), mcap (ROS 2 MCAP) or ros1 (.bag)",
    )
    conv.add_argument(
        "--no-initial-pose",
        action="store_true",
        help="do not write /initialpose (the first corrected pose, 5 cm / 3 deg std as"
        " experiment amcl-carmen starts symloc's localizer);"
        " a replay then localizes globally",
    )
    conv.add_argument(
        "--odom-alpha",
        type=options.nonnegative_float,
        default=0.0,
        help="write on /odom the noisy odometry that 'symloc experiment amcl-carmen"
        " --odom-alpha A --seed N' tracks with on this log run alone (rot-trans-rot noise of"
        " variances alpha1..4 = A on the corrected poses); default 0: the log's own odometry"
        " (in the corrected logs, the corrected poses themselves)",
    )
    conv.add_argument(
        "--odometry",
        choices=("log", *ODOMETRY_REGIMES),
        default="log",
        help="write on /odom the odometry 'symloc map build --carmen LOG --odometry R --seed N'"
        " gives SLAM (a simulated regime on the corrected increments, drawn from the log's"
        " noise stream), so 'symloc replay --build-map' maps the bag from the same input;"
        " default log: the log's own odometry",
    )
    options.add_seed(conv)
    conv.set_defaults(func=_carmen_to_bag)
    check = sub.add_parser(
        "check-params",
        help="validate a parameters YAML (nav2's amcl block or symloc's) and print it",
    )
    check.add_argument("params", type=Path, help="nav2's params file or symloc's layout")
    check.add_argument("--node-name", default="amcl", help="node block to read (default amcl)")
    check.set_defaults(func=_check)


def _run_node(args: argparse.Namespace) -> int:
    from symloc.ros.node import run_node

    ros_args = [] if args.ros_args is None else ["--ros-args", *args.ros_args]
    return run_node(args.params, ros_args, node_name=args.node_name, autostart=args.autostart)


def _setup(args: argparse.Namespace) -> int:
    import sys
    import time

    from symloc.ros.interfaces import setup_interfaces

    print(f"# symloc ros setup  prefix={sys.prefix}")
    t0 = time.perf_counter()
    results = setup_interfaces(packages=args.packages, force=args.force, workdir=args.keep_build)
    for r in results:
        print(f"  {r.package}: {r.action}" + (f" ({r.seconds:.1f} s)" if r.seconds else ""))
    print(f"done in {time.perf_counter() - t0:.1f} s")
    return 0


def _carmen_to_bag(args: argparse.Namespace) -> int:
    from symloc.errors import ConfigurationError
    from symloc.io.rosbag_carmen import carmen_to_bag

    stem = args.log.name.removesuffix(".gz").removesuffix(".log")
    bag = Path(args.out) / (stem + (".bag" if args.format == "ros1" else ""))
    options.refuse_overwriting_inputs({"log": args.log}, {"--out": bag})
    odometry = None
    if args.odom_alpha > 0.0 and args.odometry != "log":
        raise ConfigurationError(
            f"--odom-alpha {args.odom_alpha:g} and --odometry {args.odometry}: two odometry"
            " streams asked for; give one (--odom-alpha: experiment amcl-carmen's, --odometry:"
            " map build --carmen's)"
        )
    if args.odometry != "log":
        from symloc.bench.slam_runs import log_name, map_build_odometry
        from symloc.io.carmen import read_carmen

        name = log_name(args.log)
        odometry = map_build_odometry(read_carmen(args.log), name, args.odometry, args.seed)
        print(
            f"# /odom: the odometry of map build --carmen {args.log} --odometry {args.odometry}"
            f" --seed {args.seed} (noise stream SeedSequence([seed, crc32({name!r})]))"
        )
    if args.odom_alpha > 0.0:
        from symloc.bench.carmen_tracking import tracking_odometry
        from symloc.geometry import wrap_angle
        from symloc.io.carmen import read_carmen

        truth = read_carmen(args.log).laser_poses.copy()
        truth[:, 2] = wrap_angle(truth[:, 2])
        name = stem.removesuffix("-corrected")
        odometry = tracking_odometry(name, truth, args.odom_alpha, args.seed)
        print(
            f"# /odom: the corrected poses with the odometry noise of experiment amcl-carmen"
            f" --logs {name} --odom-alpha {args.odom_alpha:g} --seed {args.seed}"
        )
    notes: list[str] = []
    counts = carmen_to_bag(
        args.log,
        bag,
        fmt=args.format,
        initial_pose=not args.no_initial_pose,
        odometry=odometry,
        notes=notes,
    )
    for note in notes:
        print(f"note: {note}")
    for topic, n in sorted(counts.items()):
        print(f"  {topic}: {n} messages")
    print(f"wrote {bag}")
    return 0


def _check(args: argparse.Namespace) -> int:
    from symloc.ros.node import _read_params

    params = _read_params(args.params, args.node_name)
    print(params)
    print(f"# the localizer is built from: {params.settings()}")
    return 0


def add_sim_record_parser(sim_subparsers: Any) -> None:
    """Add ``symloc sim record`` (called from :mod:`symloc.cli.commands.sim`)."""
    rec: argparse.ArgumentParser = sim_subparsers.add_parser(
        "record",
        help="record a simulated kidnapped-robot run (scan, odom, image, ground truth) as a bag",
        description="Kidnap the simulated robot in a symmetric room inside the textured lab, let"
        " the symloc node logic localize it while a driver carries out its requests, and record"
        " every message as a ROS 2 bag (or ROS 1). The output folder gets the bag (run, or"
        " run.bag for ROS 1) and assets/: the map, the visual map, the vocabulary, node"
        " parameters and TUM trajectories.",
    )
    options.add_out(rec, "sim record", what="must be new or empty: run (the bag) and assets/")
    rec.add_argument(
        "--format",
        choices=("ros2", "mcap", "ros1"),
        default="ros2",
        help="ros2 (sqlite3 .db3, default), mcap (ROS 2 MCAP) or ros1 (.bag)",
    )
    options.add_room(rec, choices=_record_rooms(), help="symmetric room inside the lab")
    rec.add_argument("--plain", action="store_true", help="untextured lab walls")
    rec.add_argument("--compressed", action="store_true", help="images as CompressedImage (PNG)")
    rec.add_argument(
        "--max-time",
        type=options.sim_seconds,
        default=60.0,
        help="simulated seconds at most (default 60)",
    )
    rec.add_argument(
        "--particles",
        type=options.particles,
        default=2000,
        help="AMCL max_particles (default 2000)",
    )
    rec.add_argument(
        "--build-visual-map",
        action="store_true",
        help="run the node in its visual-map building mode against a new places_built.db",
    )
    options.add_seed(rec)
    rec.set_defaults(func=_sim_record)


def _record_rooms() -> tuple[str, ...]:
    from symloc.sim.rooms import ROOM_NAMES

    return tuple(r for r in options.ROOMS if r in ROOM_NAMES)


def _sim_record(args: argparse.Namespace) -> int:
    import math

    from symloc.bench.sim_record import record_sim_run

    out = Path(args.out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        from symloc.errors import ConfigurationError

        raise ConfigurationError(f"--out: {out} exists and is not an empty folder")
    bag = out / ("run.bag" if args.format == "ros1" else "run")
    print(f"# symloc sim record  seed={args.seed}  room={args.room}  format={args.format}")
    rec = record_sim_run(
        bag,
        assets=out / "assets",
        room=args.room,
        textured=not args.plain,
        seed=args.seed,
        fmt=args.format,
        compressed_images=args.compressed,
        max_time=args.max_time,
        max_particles=args.particles,
        mode="build_visual_map" if args.build_visual_map else "localize",
    )
    print(f"kidnapped to {rec.start.round(3).tolist()}; {len(rec.trajectory)} scans")
    for line in rec.steps:
        print(f"  step: {line}")
    print(f"final: {rec.final.status.value}: {rec.final.reason}")
    if rec.final.pose is not None:
        pe, he = rec.final_error
        print(f"final error vs ground truth: {pe:.4f} m, {math.degrees(he):.2f} deg")
    for topic, n in sorted(rec.counts.items()):
        print(f"  {topic}: {n} messages")
    print(f"wrote {rec.bag}")
    print(f"wrote {rec.assets}/ (params.yaml, places.db, vocabulary.bin, truth.tum, estimate.tum)")
    print(f"replay: symloc replay {rec.bag} --params {rec.params_path}")
    return 0
