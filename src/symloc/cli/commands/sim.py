"""``symloc sim render``: draw a simulated room from above with the robot's lidar and camera."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["register"]


def register(subparsers: Any) -> None:
    """Add ``sim`` with its ``render`` sub-command."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "sim", help="the simulated world (rooms, lidar, camera)"
    )
    sub = parser.add_subparsers(dest="sim_command", metavar="ACTION")
    sub.required = True
    from symloc.sim.rooms import ROOM_NAMES

    r = sub.add_parser(
        "render",
        help="top view (walls, robot, lidar points) and the camera image as one PNG",
        description="Build a room, put the robot in it, simulate one lidar scan and one camera "
        "image, and draw them.",
    )
    options.add_room(r, choices=ROOM_NAMES, help="room shape")
    r.add_argument(
        "--gv",
        type=options.positive_float,
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
    r.add_argument("--furniture", type=options.nonnegative_int, default=0, help="number of boxes")
    r.add_argument(
        "--tables", type=options.nonnegative_int, default=0, help="number of round tables"
    )
    options.add_angle(
        r, "--hfov", default=65.0, help="camera horizontal field of view", dest="hfov"
    )
    r.add_argument("--gain", type=options.positive_float, default=1.0, help="camera lighting gain")
    options.add_seed(r)
    options.add_out(r, "sim render", what="scene.png (top view + camera) and camera.png")
    r.set_defaults(func=_render)
    from symloc.cli.commands.ros import add_sim_record_parser  # `sim record` (ROS part)

    add_sim_record_parser(sub)


def _render(args: argparse.Namespace) -> int:
    import numpy as np

    from symloc.figures.world import scene_figure
    from symloc.geometry import transform_points
    from symloc.sim.camera import Camera
    from symloc.sim.lidar import LIDAR_MOUNT_HEIGHT, PRESETS, simulate_scan
    from symloc.sim.rooms import build_room

    rng = np.random.default_rng(args.seed)
    print(f"# symloc sim render  seed={args.seed}")
    room = build_room(
        args.room,
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
    preset = PRESETS[args.lidar]
    camera = Camera(hfov=args.hfov, gain=args.gain)
    print(
        f"#   room={room.name} gv={room.gv_distance:.3f} m order={room.order} lab={not args.no_lab}"
        f" textured={not args.plain} door={room.door} furniture={room.n_furniture}"
    )
    print(f"#   pose=({pose[0]:.3f}, {pose[1]:.3f}, {rel[2]:.1f} deg) lidar={preset.name}")
    print(
        f"#   camera {camera.width}x{camera.height} hfov={math.degrees(args.hfov):g} deg"
        f" gain={args.gain}"
    )
    scan = simulate_scan(room.world, pose, preset, rng)
    image = camera.render(room.world, pose, rng)
    pts = scan.to_points()
    world_pts = transform_points(pose, pts.points)
    print(
        f"scan: {len(scan)} beams, {pts.points.shape[0]} points, {pts.n_invalid} invalid,"
        f" {pts.n_no_return} no return"
    )
    out = scene_figure(
        room.world,
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

    camera_png = Path(args.out) / "camera.png"
    camera_png.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(camera_png), image[:, :, ::-1])
    print(f"wrote {camera_png}")
    return 0
