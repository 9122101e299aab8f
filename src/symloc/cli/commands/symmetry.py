"""``symloc symmetry judge``: judge the symmetry of the room around the robot from one scan.

The scan comes from a CARMEN log (``--carmen PATH [--index N]``), a ROS bag topic
(``--bag PATH [--topic /scan] [--index N]``) or, when neither is given, a simulated room
(``--room square --gv 3 --pose X Y DEG``; defaults: the paper's 3 m x 3 m square, the robot at
0.3 m, 0.2 m, 30 deg from its centre). Prints the :class:`SymmetryReport` (and the ground
truth for a simulated room); ``--png`` saves a picture of the scan with its lines and centre,
``--json`` the report.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from symloc.cli import options

__all__ = ["register"]

#: The simulated room's default G-V distance [m] (the paper's 3 m x 3 m square) and robot pose
#: (x [m], y [m], heading [deg] from the room centre).
DEFAULT_GV = 1.5 * math.sqrt(2.0)
DEFAULT_POSE = (0.3, 0.2, 30.0)


def _judge_rooms() -> tuple[str, ...]:
    from symloc.sim.rooms import ROOM_NAMES

    return tuple(r for r in options.ROOMS if r in ROOM_NAMES)


def register(subparsers: Any) -> None:
    """Add ``symmetry`` with its ``judge`` sub-command."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "symmetry", help="symmetry judgement of one laser scan (Algorithm 1, generalised)"
    )
    sub = parser.add_subparsers(dest="symmetry_command", metavar="ACTION")
    sub.required = True
    j = sub.add_parser(
        "judge",
        help="judge one scan from a CARMEN log, a ROS bag or a simulated room",
        description="Judge whether the room around the robot is symmetric (regular polygon, "
        "circle, rectangle, hallway), with the symmetry order, the centre in the sensor frame "
        "and the reason. A scan of under 360 degrees gives 'unknown' unless --partial-view.",
    )
    src = j.add_mutually_exclusive_group()
    src.add_argument("--carmen", type=Path, metavar="PATH", help="CARMEN log (.log or .log.gz)")
    src.add_argument("--bag", type=Path, metavar="PATH", help="ROS 1 .bag or ROS 2 bag folder")
    options.add_room(j, choices=_judge_rooms(), help="without --carmen or --bag: simulated room")
    j.add_argument(
        "--index",
        type=options.integer,
        default=0,
        help="scan index in the log / topic, from 0 (default 0); in a CARMEN log a negative"
        " index counts from the end (-1: the last scan)",
    )
    j.add_argument("--topic", default=None, help="bag: LaserScan topic (default: the first)")
    j.add_argument(
        "--gv",
        type=options.gv_distance,
        default=None,
        help=f"room: G-V distance [m] (default {DEFAULT_GV:.3f}, a 3 m x 3 m square)",
    )
    j.add_argument(
        "--pose",
        type=options.finite_float,
        nargs=3,
        default=None,
        metavar=("X", "Y", "DEG"),
        help="room: robot pose in the room frame (centre at 0 0) [m m deg]",
    )
    options.add_lidar(j, help="room: simulated lidar")
    j.add_argument("--door", action="store_true", help="room: open a door in the first wall")
    j.add_argument(
        "--furniture",
        type=options.items,
        default=0,
        help="room: number of boxes inside",
    )
    options.add_seed(j)
    j.add_argument(
        "--range-sigma",
        type=options.positive_float,
        default=None,
        help="range noise [m] the tolerances follow from (default: the preset's for a room, "
        "0.01 otherwise)",
    )
    j.add_argument(
        "--range-sigma-relative",
        type=options.nonnegative_float,
        default=None,
        help="relative range noise (0)",
    )
    j.add_argument(
        "--centroid", choices=["area", "mean"], default="area", help="centroid method (area)"
    )
    j.add_argument(
        "--partial-view",
        action="store_true",
        help="judge scans under 360 degrees for a hallway (the unseen part is assumed)",
    )
    j.add_argument(
        "--png", type=options.output_file, default=None, metavar="PATH", help="save a figure"
    )
    j.add_argument(
        "--json", type=options.output_file, default=None, metavar="PATH", help="save the report"
    )
    j.set_defaults(func=_judge)


def _error(text: str) -> int:
    print(f"symloc symmetry judge: error: {text}", file=sys.stderr)
    return 2


def _fmt(v: Any) -> str:
    a = np.asarray(v, dtype=np.float64)
    if a.ndim == 0:
        return f"{float(a):.3f}"
    return "(" + ", ".join(f"{x:.3f}" for x in a.ravel()) + ")"


def _judge(args: argparse.Namespace) -> int:
    from symloc.bench.scan_sources import bag_scan, carmen_scan, room_scan
    from symloc.sim.symmetry_truth import truth_order
    from symloc.symmetry import SymmetryConfig, judge_symmetry, scan_lines

    if args.carmen is None and args.bag is None:
        src = room_scan(
            args.room,
            DEFAULT_GV if args.gv is None else args.gv,
            DEFAULT_POSE if args.pose is None else args.pose,
            sensor=args.lidar,
            rng=args.seed,
            door=args.door,
            furniture=args.furniture,
        )
    else:
        room_only = [
            n
            for n, bad in (
                ("--gv", args.gv is not None),
                ("--pose", args.pose is not None),
                ("--door", args.door),
                ("--furniture", args.furniture != 0),
            )
            if bad
        ]
        if args.room != options.DEFAULT_ROOM:
            room_only.insert(0, "--room")
        if room_only:
            return _error(f"{', '.join(room_only)} only apply to a simulated room")
        if args.carmen is not None:
            if args.topic is not None:
                return _error("--topic only applies to --bag")
            src = carmen_scan(args.carmen, args.index)
        else:
            src = bag_scan(args.bag, args.topic, args.index)
    sigma = args.range_sigma if args.range_sigma is not None else (src.sigma or 0.01)
    rel = (
        args.range_sigma_relative
        if args.range_sigma_relative is not None
        else (src.sigma_relative if src.sigma is not None else 0.0)
    )
    cfg = SymmetryConfig(
        range_sigma=sigma, range_sigma_relative=rel, partial_view=bool(args.partial_view)
    )
    report = judge_symmetry(src.scan, config=cfg, centroid=args.centroid)
    scan = src.scan
    fov = math.degrees(scan.angle_increment * len(scan))
    print(f"# symloc symmetry judge: {src.source}; seed {args.seed}")
    print(
        f"#   {len(scan)} beams over {fov:.0f} deg, range {scan.range_min:g}..{scan.range_max:g}"
        f" m; noise sigma {sigma:g} m + {rel:g} r; centroid {args.centroid};"
        f" partial_view {cfg.partial_view}"
    )
    order = options.order_text(report.order)
    print(f"kind        {report.kind}")
    print(f"symmetric   {report.symmetric}")
    print(f"order       {order}")
    print(f"regular     {report.regular}")
    print(f"centre      {_fmt(report.center)} m (sensor frame)")
    print(f"G-V         {_fmt(report.gv_distance)} m")
    print(f"residual    {_fmt(report.residual)} m (tolerance {_fmt(report.tolerance)} m)")
    print(f"points      {report.n_points}, lines {report.n_lines}, corners {report.n_corners}")
    if report.n_corners:
        print("corners     " + " ".join(_fmt(c) for c in report.corners))
    print(f"reason      {report.reason}")
    if src.truth:
        t = src.truth
        t_order = options.order_text(truth_order(t["order"]))
        err = float(np.hypot(*(report.center - t["center"])))
        where = f", centre error {err:.3f} m" if np.isfinite(err) else ""
        print(
            f"truth       {t['kind']}, order {t_order}, centre {_fmt(t['center'])} m (sensor"
            f" frame), G-V {t['gv_distance']:.3f} m{where}"
        )
    if args.png is not None:
        options.refuse_overwriting_inputs(
            {"--carmen": args.carmen, "--bag": args.bag}, {"--png": args.png}
        )
        from symloc.figures.symmetry import plot_judgement

        out = plot_judgement(scan, report, args.png, lines=scan_lines(scan, cfg))
        print(f"wrote {out}")
    if args.json is not None:
        data = {"source": src.source, "index": src.index, "report": report.to_dict()}
        if src.truth:
            data["truth"] = {**src.truth, "center": [float(v) for v in src.truth["center"]]}
        options.refuse_overwriting_inputs(
            {"--carmen": args.carmen, "--bag": args.bag}, {"--json": args.json}
        )
        options.write_json(args.json, data)
        print(f"wrote {args.json}")
    return 0
