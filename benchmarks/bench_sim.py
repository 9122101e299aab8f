"""Benchmark the simulator: lidar ray casting and camera rendering.

World: the paper's square room (3 m x 3 m of 0.4 m boards) with 4 furniture boxes inside a
12-segment textured lab; 32 wall segments in all. Times one 360-beam scan (LDS-01) and one
800-beam scan (RPLIDAR A2), both the bare ray cast and ``simulate_scan`` (ray cast + noise +
dropouts + LaserScan), the same scans from a ``realistic`` regime's lidar (all faults, motion
skew while driving at 0.3 m/s and turning at 0.5 rad/s, in the same room with one wall made
glass and one dark), one 640 x 480 camera image with ideal sensors and one with the
``realistic`` regime (distortion, vignetting, exposure and white balance, motion blur), and the
cost of building one procedural wall texture. Prints medians in ms.
Targets (issue 2 and issue 11): a scan under 1 ms, an image under 30-40 ms.

``--results PATH`` also writes the rows (and the ORB keypoint counts) as a results file with the
command, commit, date, machine and load (the README's: ``docs/results/bench_sim.json``).

Run: ``python benchmarks/bench_sim.py [--repeats R] [--seed S] [--results PATH]``
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from symloc.sim.camera import Camera
from symloc.sim.lidar import LDS01, LIDAR_MOUNT_HEIGHT, RPLIDAR_A2, simulate_scan
from symloc.sim.poster import procedural_texture
from symloc.sim.raycast import raycast
from symloc.sim.regimes import REGIMES
from symloc.sim.rooms import build_room
from symloc.sim.textures import load_photo
from symloc.sim.world import MATERIAL_DARK, MATERIAL_GLASS, World


def median_ms(fn: Callable[[int], object], repeats: int) -> tuple[float, float]:
    """Median wall and CPU time [ms] of ``fn(i)`` over ``repeats`` calls, after a warm-up call.

    On a shared machine the wall time includes waiting for a core; the process CPU time
    does not.
    """
    fn(0)
    wall = []
    cpu = []
    for i in range(repeats):
        t0 = time.perf_counter()
        c0 = time.process_time()
        fn(i)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - t0)
    return float(np.median(wall) * 1e3), float(np.median(cpu) * 1e3)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=200, help="timed calls per figure")
    parser.add_argument("--seed", type=int, default=0, help="random seed (printed)")
    parser.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write a results file (the README's: docs/results/bench_sim.json)",
    )
    args = parser.parse_args()
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    rng = np.random.default_rng(args.seed)
    room = build_room("square", 1.5 * math.sqrt(2), furniture=4, rng=args.seed)
    world = room.world
    poses = np.column_stack(
        [rng.uniform(-0.8, 0.8, 64), rng.uniform(-0.8, 0.8, 64), rng.uniform(-np.pi, np.pi, 64)]
    )
    print(f"# bench_sim seed={args.seed} repeats={args.repeats} load={os.getloadavg()[0]:.2f}")
    print(
        f"# world: {world.n_walls} wall segments, {world.n_circles} circles (square + 4 boxes + lab)"
    )
    rows: list[tuple[str, tuple[float, float], float]] = []
    for preset in (LDS01, RPLIDAR_A2):
        angles = preset.angles
        rows.append(
            (
                f"raycast {preset.n_beams} beams",
                median_ms(
                    lambda i, a=angles: raycast(
                        world,
                        poses[i % 64, :2],
                        poses[i % 64, 2] + a,
                        min_height=LIDAR_MOUNT_HEIGHT,
                    ),
                    args.repeats,
                ),
                1.0,
            )
        )
        rows.append(
            (
                f"simulate_scan {preset.name} ({preset.n_beams} beams)",
                median_ms(
                    lambda i, p=preset: simulate_scan(world, poses[i % 64], p, rng), args.repeats
                ),
                1.0,
            )
        )
    realistic = REGIMES["realistic"]
    mats = np.asarray(world.wall_materials).copy()
    mats[0] = MATERIAL_GLASS
    mats[1] = MATERIAL_DARK
    faulty = World(
        world.walls,
        world.wall_heights,
        mats,
        world.circles,
        world.circle_heights,
        world.circle_materials,
        world.wall_tex_u,
    )
    for preset in (LDS01, RPLIDAR_A2):
        lidar = realistic.lidar(preset, rng)
        rows.append(
            (
                f"realistic lidar {preset.name} (all faults)",
                median_ms(
                    lambda i, ld=lidar: ld.scan(faulty, poses[i % 64], twist=(0.3, 0.5)),
                    args.repeats,
                ),
                1.0,
            )
        )
    cam = Camera()
    rows.append(
        (
            f"camera render {cam.width}x{cam.height}",
            median_ms(lambda i: cam.render(world, poses[i % 64], rng), max(20, args.repeats // 5)),
            30.0,
        )
    )
    real_cam = realistic.camera(rng)
    session = realistic.camera_session(rng, "query")
    rows.append(
        (
            f"realistic camera {real_cam.width}x{real_cam.height}",
            median_ms(
                lambda i: real_cam.render(
                    world, poses[i % 64], rng, conditions=session.conditions(rng), twist=(0.2, 0.5)
                ),
                max(20, args.repeats // 5),
            ),
            40.0,
        )
    )
    for k in range(16):
        load_photo(k, 768)
    rows.append(
        (
            "one procedural wall texture 768x768",
            median_ms(lambda i: procedural_texture(16 + i, 768, load_photo), 40),
            50.0,
        )
    )
    print(f"{'what':<42} {'wall ms':>9} {'cpu ms':>9} {'target':>7}  (medians)")
    for name, (wall, cpu), target in rows:
        flag = "" if wall < target else "  (wall over target)"
        print(f"{name:<42} {wall:>9.3f} {cpu:>9.3f} {target:>7.1f}{flag}")
    orb = orb_counts(args.seed)
    if args.results is not None:
        from symloc.bench.results_file import write_bench_results

        figures: dict[str, Any] = {
            "rows": [
                {"what": name, "wall_ms": round(w, 4), "cpu_ms": round(c, 4), "target_ms": t}
                for name, (w, c), t in rows
            ],
            "orb_keypoints": orb,
            "world": {"walls": int(world.n_walls), "circles": int(world.n_circles)},
        }
        written = write_bench_results(
            args.results,
            clock=clock,
            settings={"seed": args.seed, "repeats": args.repeats},
            figures=figures,
            argv=sys.argv,
        )
        print(f"wrote {written}")


def orb_counts(seed: int) -> dict[str, list[int]]:
    """ORB keypoints (cv2.ORB_create(500)) in camera images from the centre of the paper's
    empty room, facing the four wall middles, with the textured and with the plain lab;
    returns them by lab (``"textured lab"``, ``"plain lab"``)."""
    import cv2

    orb = cv2.ORB_create(500)
    cam = Camera()
    print("# ORB keypoints of 500, camera at the room centre facing 0, 90, 180, -90 deg")
    out: dict[str, list[int]] = {}
    for textured in (True, False):
        room = build_room("square", 1.5 * math.sqrt(2), textured=textured)
        counts = []
        for th in (0.0, math.pi / 2, math.pi, -math.pi / 2):
            img = cam.render(room.world, [0.0, 0.0, th], seed)
            counts.append(len(orb.detect(cv2.cvtColor(img, cv2.COLOR_RGB2GRAY), None)))
        print(f"{'textured lab' if textured else 'plain lab':<42} {counts}")
        out["textured lab" if textured else "plain lab"] = counts
    return out


if __name__ == "__main__":
    main()
