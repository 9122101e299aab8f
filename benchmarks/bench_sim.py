"""Benchmark the simulator: lidar ray casting and camera rendering.

World: the paper's square room (3 m x 3 m of 0.4 m boards) with 4 furniture boxes inside a
12-segment textured lab; 32 wall segments in all. Times one 360-beam scan (LDS-01) and one
800-beam scan (RPLIDAR A2), both the bare ray cast and ``simulate_scan`` (ray cast + noise +
dropouts + LaserScan), and one 640 x 480 camera image. Prints medians in ms.
Targets (issue 2): a scan under 1 ms, an image under 30 ms.

Run: ``python benchmarks/bench_sim.py [--repeats R] [--seed S]``
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

import numpy as np

from symloc.sim.camera import Camera
from symloc.sim.lidar import LDS01, LIDAR_MOUNT_HEIGHT, RPLIDAR_A2, simulate_scan
from symloc.sim.raycast import raycast
from symloc.sim.rooms import build_room


def median_ms(fn: Callable[[int], object], repeats: int) -> float:
    """Median wall time [ms] of ``fn(i)`` over ``repeats`` calls, after one warm-up call."""
    fn(0)
    times = []
    for i in range(repeats):
        t0 = time.perf_counter()
        fn(i)
        times.append(time.perf_counter() - t0)
    return float(np.median(times) * 1e3)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=200, help="timed calls per figure")
    parser.add_argument("--seed", type=int, default=0, help="random seed (printed)")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    room = build_room("square", 1.5 * math.sqrt(2), furniture=4, rng=args.seed)
    world = room.world
    poses = np.column_stack(
        [rng.uniform(-0.8, 0.8, 64), rng.uniform(-0.8, 0.8, 64), rng.uniform(-np.pi, np.pi, 64)]
    )
    print(f"# bench_sim seed={args.seed} repeats={args.repeats}")
    print(
        f"# world: {world.n_walls} wall segments, {world.n_circles} circles (square + 4 boxes + lab)"
    )
    rows = []
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
    cam = Camera()
    rows.append(
        (
            f"camera render {cam.width}x{cam.height}",
            median_ms(lambda i: cam.render(world, poses[i % 64], rng), max(20, args.repeats // 5)),
            30.0,
        )
    )
    print(f"{'what':<42} {'median ms':>10} {'target ms':>10}")
    for name, ms, target in rows:
        flag = "" if ms < target else "  (over target)"
        print(f"{name:<42} {ms:>10.3f} {target:>10.1f}{flag}")


if __name__ == "__main__":
    main()
