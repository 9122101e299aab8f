"""``symloc sim``: draw a simulated world (``render``), write a generated world as a world file
(``world``), and draw a gallery of generated worlds with their computed symmetry (``gallery``)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["register"]


def register(subparsers: Any) -> None:
    """Add ``sim`` with its ``render``, ``world`` and ``gallery`` sub-commands."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "sim", help="the simulated world (rooms, lidar, camera)"
    )
    sub = parser.add_subparsers(dest="sim_command", metavar="ACTION")
    sub.required = True
    from symloc.sim.rooms import ROOM_NAMES

    r = sub.add_parser(
        "render",
        help="top view (walls, robot, lidar points) and the camera image as one PNG",
        description="Build a room (--room, with the options below) or load a world file "
        "(--world), put the robot in it, simulate one lidar scan and one camera image, and draw "
        "them.",
    )
    which = r.add_mutually_exclusive_group()
    options.add_room(which, choices=ROOM_NAMES, help="room shape")
    which.add_argument(
        "--world",
        type=Path,
        default=None,
        help="a world file (YAML, see docs/world_files.md); --gv, --no-lab, --plain, --door, "
        "--furniture and --tables apply to --room only",
    )
    r.add_argument(
        "--time",
        type=options.finite_float,
        default=0.0,
        help="time [s]: where the world's people are (default 0)",
    )
    r.add_argument(
        "--gv",
        type=options.gv_distance,
        default=1.5 * math.sqrt(2),
        help="G-V distance, centre to vertex [m] (default: the paper's 3 m x 3 m square)",
    )
    r.add_argument(
        "--pose",
        type=options.finite_float,
        nargs=3,
        metavar=("X", "Y", "THETA_DEG"),
        default=None,
        help="robot pose relative to the room centre [m, m, deg] (default 0.3 0.2 30)",
    )
    options.add_lidar(r)
    r.add_argument("--no-lab", action="store_true", help="no lab around the room (tall walls)")
    r.add_argument("--plain", action="store_true", help="untextured walls (no photographs)")
    r.add_argument("--door", action="store_true", help="a 0.8 m door gap in the bottom wall")
    r.add_argument("--furniture", type=options.items, default=0, help="number of boxes")
    r.add_argument("--tables", type=options.items, default=0, help="number of round tables")
    options.add_angle(
        r, "--hfov", default=65.0, help="camera horizontal field of view", dest="hfov"
    )
    r.add_argument("--gain", type=options.positive_float, default=1.0, help="camera lighting gain")
    options.add_seed(r)
    options.add_out(r, "sim render", what="scene.png (top view + camera) and camera.png")
    r.set_defaults(func=_render)
    from symloc.cli.commands.ros import add_sim_record_parser  # `sim record` (ROS part)

    add_sim_record_parser(sub)
    _add_world_parser(sub)
    _add_gallery_parser(sub)


def _add_world_parser(sub: Any) -> None:
    from symloc.sim.generator import FAMILIES
    from symloc.sim.rooms import ROOM_NAMES

    w = sub.add_parser(
        "world",
        help="write a generated world (or a named room) as a world file to edit",
        description="Draw a world of a generator family from a seed (or take one of the named "
        "rooms) and write it as YAML that `symloc sim render --world` and the bench load. "
        "Prints the computed symmetry order, centre and G-V distance.",
    )
    src = w.add_mutually_exclusive_group(required=True)
    src.add_argument("--family", choices=sorted(FAMILIES), help="generator family")
    options.add_room(src, choices=ROOM_NAMES, help="a named room (as `sim render --room`)")
    src.add_argument("--list", action="store_true", help="list the families and exit")
    options.add_seed(w)
    pert = w.add_mutually_exclusive_group()
    pert.add_argument(
        "--perturb",
        dest="perturb",
        action="store_true",
        default=None,
        help="always perturb (default: the seed decides)",
    )
    pert.add_argument(
        "--no-perturb", dest="perturb", action="store_false", help="the bare family room"
    )
    w.add_argument(
        "--gv", type=options.gv_distance, default=3.0, help="G-V distance [m] for --room"
    )
    w.add_argument("--no-lab", action="store_true", help="--room: tall walls, no lab")
    options.add_out(w, "sim world", what="<world name>.yaml (also printed)")
    w.set_defaults(func=_world)


def _add_gallery_parser(sub: Any) -> None:
    from symloc.sim.generator import FAMILIES

    g = sub.add_parser(
        "gallery",
        help="draw generated worlds in a grid with their computed symmetry order",
        description="Generate COUNT worlds going round the families (alternately bare and "
        "perturbed) from --seed on, and draw them from above with their computed order.",
    )
    options.add_out(g, "sim gallery", what="worlds_gallery.png")
    g.add_argument(
        "--count", type=options.gallery_count, default=16, help="number of worlds (default 16)"
    )
    g.add_argument(
        "--families",
        nargs="+",
        choices=sorted(FAMILIES),
        default=None,
        help="families to draw from (default all)",
    )
    options.add_seed(g)
    g.set_defaults(func=_gallery)


def _render(args: argparse.Namespace) -> int:
    import numpy as np

    from symloc.figures.world import scene_figure
    from symloc.geometry import transform_points
    from symloc.sim.camera import Camera
    from symloc.sim.lidar import LIDAR_MOUNT_HEIGHT, PRESETS, simulate_scan
    from symloc.sim.rooms import build_room
    from symloc.sim.world_file import load_world_file

    rng = np.random.default_rng(args.seed)
    print(f"# symloc sim render  seed={args.seed}")
    if args.world is not None:
        room = load_world_file(args.world).build()
        print(f"#   world file {args.world}")
    else:
        room = build_room(
            args.room or "square",
            args.gv,
            lab=not args.no_lab,
            textured=not args.plain,
            door=args.door,
            furniture=args.furniture,
            tables=args.tables,
            rng=args.seed,
        )
    rel = (0.3, 0.2, 30.0) if args.pose is None else args.pose
    pose = np.array([room.center[0] + rel[0], room.center[1] + rel[1], math.radians(rel[2])])
    if args.pose is None and not room.is_free(pose[None, :2])[0]:
        pose = room.sample_pose(rng)  # the default spot is taken: any free pose
        rel = (*(pose[:2] - room.center), math.degrees(pose[2]))
    preset = PRESETS[args.lidar]
    camera = Camera(hfov=args.hfov, gain=args.gain)
    print(
        f"#   room={room.name} gv={room.gv_distance:.3f} m order={room.order}"
        f" shape_order={room.shape_order} wall_height={room.wall_height} door={room.door}"
        f" furniture={room.n_furniture} people={len(room.people)} t={args.time} s"
    )
    print(f"#   pose=({pose[0]:.3f}, {pose[1]:.3f}, {rel[2]:.1f} deg) lidar={preset.name}")
    print(
        f"#   camera {camera.width}x{camera.height} hfov={math.degrees(args.hfov):g} deg"
        f" gain={args.gain}"
    )
    world = room.world_at(args.time)
    scan = simulate_scan(world, pose, preset, rng)
    image = camera.render(world, pose, rng)
    pts = scan.to_points()
    world_pts = transform_points(pose, pts.points)
    print(
        f"scan: {len(scan)} beams, {pts.points.shape[0]} points, {pts.n_invalid} invalid,"
        f" {pts.n_no_return} no return"
    )
    out = scene_figure(
        world,
        pose,
        world_pts,
        image,
        Path(args.out) / "scene.png",
        hfov=camera.hfov,
        lidar_height=LIDAR_MOUNT_HEIGHT,
        title=f"{room.name}, G-V {room.gv_distance:.2f} m, {preset.name}",
    )
    print(f"wrote {out}")
    import cv2

    from symloc.files.atomic import atomic_path

    camera_png = Path(args.out) / "camera.png"
    with atomic_path(camera_png) as tmp:
        if not cv2.imwrite(str(tmp), image[:, :, ::-1]):
            raise OSError(f"{camera_png}: OpenCV cannot write the image")
    print(f"wrote {camera_png}")
    return 0


def _world(args: argparse.Namespace) -> int:
    from symloc.sim.generator import FAMILIES, generate_world
    from symloc.sim.world_file import room_spec, save_world_file

    if args.list:
        for name, fam in FAMILIES.items():
            nature = (
                "symmetric"
                if fam.symmetric
                else "near-symm."
                if fam.nearly_symmetric
                else "asymmetric"
            )
            print(f"{name:<15} {nature:<11} {fam.description}")
        return 0
    if args.family is not None:
        print(f"# symloc sim world  family={args.family} seed={args.seed} perturb={args.perturb}")
        spec = generate_world(args.family, args.seed, perturb=args.perturb)
        header = (
            f"symloc sim world --family {args.family} --seed {args.seed}"
            + {None: "", True: " --perturb", False: " --no-perturb"}[args.perturb]
        )
    else:
        print(f"# symloc sim world  room={args.room} gv={args.gv} lab={not args.no_lab}")
        spec = room_spec(args.room, args.gv, lab=not args.no_lab)
        header = f"symloc sim world --room {args.room} --gv {args.gv}" + (
            " --no-lab" if args.no_lab else ""
        )
    room = spec.build()
    c = room.center
    summary = (
        f"order {room.order} (outline {room.shape_order}), centre ({c[0]:.3f}, {c[1]:.3f}) m,"
        f" G-V {room.gv_distance:.3f} m"
    )
    print(f"#   {spec.name}: {spec.description}")
    print(f"#   computed: {summary}")
    print(spec.to_yaml(), end="")
    target = Path(args.out) / f"{spec.name}.yaml"
    target.parent.mkdir(parents=True, exist_ok=True)
    out = save_world_file(spec, target, header=f"{header}\n{spec.description}\n{summary}")
    print(f"wrote {out}")
    return 0


def _gallery(args: argparse.Namespace) -> int:
    from symloc.figures.worlds import gallery_figure
    from symloc.sim.generator import FAMILIES, generate_world

    families = args.families or list(FAMILIES)
    print(f"# symloc sim gallery  seed={args.seed} count={args.count} families={families}")
    rooms = []
    for i in range(args.count):
        fam = families[i % len(families)]
        seed = args.seed + i
        perturb = i % 2 == 1
        spec = generate_world(fam, seed, perturb=perturb)
        room = spec.build()
        rooms.append((f"{spec.name}{' (perturbed)' if perturb else ''}", room))
        print(f"{spec.name:<22} order {room.order:>2}  {spec.description}")
    out = gallery_figure(rooms, args.out / "worlds_gallery.png")
    print(f"wrote {out}")
    return 0
