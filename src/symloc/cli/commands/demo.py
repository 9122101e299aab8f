"""``symloc demo``: map a symmetric room, kidnap the robot, plain AMCL vs symloc, one picture."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["register", "run"]

ROOMS = (
    "triangle",
    "square",
    "pentagon",
    "hexagon",
    "circle",
    "rectangle",
    "hallway",
    "hallway_40m",
)

#: The default story (no --room, no --world): the packaged world ``square_with_box`` (a 4 m
#: square with a box and a round table: nearly symmetric, the rooms the paper describes) at
#: seed 2, where plain AMCL ends confident on a pose 2.1 m off, symloc decides from one image
#: where the robot stands and the paper's path, which needs a symmetric room, cannot decide.
DEFAULT_WORLD = "square_with_box"
DEFAULT_ROOM = None
DEFAULT_SEED = 2


def register(subparsers: Any) -> None:
    """Add ``demo`` to the ``symloc`` command."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "demo",
        help="kidnapped robot in a symmetric room: plain AMCL vs symloc (table + PNG)",
    )
    where = parser.add_mutually_exclusive_group()
    options.add_room(
        where,
        choices=ROOMS,
        help="symmetric room inside the lab",
        default=DEFAULT_ROOM,
        default_help=f"the packaged world {DEFAULT_WORLD}: a square with a box and a table",
    )
    where.add_argument(
        "--world",
        type=Path,
        default=None,
        metavar="FILE",
        help="a world file (YAML, see docs/world_files.md) instead of a built-in room",
    )
    options.add_seed(parser, default=DEFAULT_SEED)
    options.add_out(parser, "demo", what="the map, visual map and demo_<room>.png")
    parser.add_argument(
        "--untextured", action="store_true", help="plain lab walls (the camera's failure case)"
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symloc.bench.demo import run_demo
    from symloc.figures.demo import demo_figure

    t0 = time.perf_counter()
    room: Any = args.room
    world = args.world
    if world is None and room is None:
        from importlib.resources import files

        world = Path(str(files("symloc") / "data" / "worlds" / f"{DEFAULT_WORLD}.yaml"))
    if world is not None:
        import dataclasses

        from symloc.sim.world_file import load_world_file

        spec = load_world_file(world)
        if args.untextured:  # plain walls whatever the file's lab says
            spec = dataclasses.replace(
                spec, lab=dataclasses.replace(spec.lab, textured=False, textures=())
            )
        room = spec.build()
    print(
        f"# symloc demo: {'world ' + str(world) if world else 'room ' + args.room}, "
        f"seed {args.seed}, {'untextured' if args.untextured else 'textured'} lab, "
        f"out {args.out}"
    )
    res = run_demo(room, seed=args.seed, workdir=args.out, textured=not args.untextured)
    scen = res.scenario
    print(
        f"# lidar {scen.preset.name}; symloc AMCL max_particles {scen.amcl_params.max_particles}; "
        f"plain AMCL nav2 defaults (max_particles {scen.plain_amcl_params().max_particles}); "
        f"robot odometry noise alpha1..4 = {scen.odom_alpha} (both AMCLs matched)"
    )
    for note in scen.notes:
        print(f"# {note}")
    if scen.mapped is not None:
        p = scen.mapped.place
        print(
            f"# mapping stage: {p.kind} order {p.order} G-V {p.gv_distance:.3f} m, "
            f"{p.m} images, centre reached within {1000 * scen.mapped.centering.error:.1f} mm"
        )
    print(f"# kidnapped to {_pose(res.symloc.true_start)} (true pose)")
    print()
    width = max(len(k) for k, _ in res.rows())
    for key, value in res.rows():
        print(f"{key:<{width}}  {value}")
    path = demo_figure(res.story, Path(args.out) / f"demo_{res.room}.png")
    print()
    t = res.timings
    print(f"wrote {path}")
    print(
        f"time: maps {t['maps']:.1f} s, symloc {t['symloc']:.1f} s, plain AMCL {t['amcl']:.1f} s, "
        f"the paper's path {t['paper']:.1f} s, "
        f"total {time.perf_counter() - t0:.1f} s"
    )
    scen.close()
    return 0


def _pose(p: Any) -> str:
    import math

    return f"({p[0]:+.3f} m, {p[1]:+.3f} m, {math.degrees(p[2]):+.1f} deg)"
