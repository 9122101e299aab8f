"""Benchmark the ROS interop: message conversions, the node logic per scan, DDS round trips.

- conversions: one 800-beam LaserScan and one 640 x 480 rgb8 Image from a CDR message to symloc
  types, and an rclpy Image built from a field dict (when rclpy is installed);
- node logic: NodeCore per scan (conversion + odometry interpolation + the full localizer) over
  a recorded simulated kidnapped-robot run (replay throughput);
- DDS (when rclpy is installed): publisher -> subscriber latency on loopback for a 800-beam
  LaserScan and a 640 x 480 Image, in one process, Fast DDS, random domain id.

Prints medians (wall and process CPU) in ms. Run: ``python benchmarks/bench_ros.py
[--results PATH]``: ``--results`` also writes the figures as a results file with the run's
command, commit, date, machine and load (:mod:`symloc.bench.results_file`; the README's is
``docs/results/bench_ros.json``, rendered by ``python -m symloc.readme``).
"""

from __future__ import annotations

import argparse
import math
import os
import random
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_typestore

from symloc.msgs import (
    build_rosbags,
    image_from_msg,
    image_to_fields,
    scan_from_msg,
    scan_to_fields,
)
from symloc.scan import LaserScan


def median_ms(fn: Callable[[int], object], repeats: int) -> tuple[float, float]:
    """Median wall and CPU time [ms] of ``fn(i)`` over ``repeats`` calls, after a warm-up."""
    fn(0)
    wall, cpu = [], []
    for i in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn(i)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(wall)), 1e3 * float(np.median(cpu))


def bench_conversions(repeats: int) -> dict[str, Any]:
    """Median ms of the message conversions: ``{name: {"wall_ms", "cpu_ms"}}``."""
    out: dict[str, Any] = {}
    ts = get_typestore(Stores.ROS2_HUMBLE)
    rng = np.random.default_rng(0)
    scan = LaserScan(-math.pi, 2 * math.pi / 800, 0.15, 12.0, rng.uniform(0.5, 6, 800), stamp=1.0)
    raw = ts.serialize_cdr(
        build_rosbags(ts, "sensor_msgs/msg/LaserScan", scan_to_fields(scan)),
        "sensor_msgs/msg/LaserScan",
    )
    img = rng.integers(0, 256, (480, 640, 3), dtype=np.uint8)
    raw_img = ts.serialize_cdr(
        build_rosbags(ts, "sensor_msgs/msg/Image", image_to_fields(img, stamp=1.0)),
        "sensor_msgs/msg/Image",
    )
    w, c = median_ms(
        lambda i: scan_from_msg(ts.deserialize_cdr(raw, "sensor_msgs/msg/LaserScan")), repeats
    )
    print(f"LaserScan 800 beams, CDR -> symloc:      {w:7.3f} ms wall  {c:7.3f} ms cpu")
    out["scan_cdr_to_symloc"] = {"wall_ms": w, "cpu_ms": c, "beams": 800}
    w, c = median_ms(
        lambda i: image_from_msg(ts.deserialize_cdr(raw_img, "sensor_msgs/msg/Image")), repeats
    )
    print(f"Image 640x480 rgb8, CDR -> RGB array:    {w:7.3f} ms wall  {c:7.3f} ms cpu")
    out["image_cdr_to_rgb"] = {"wall_ms": w, "cpu_ms": c, "width": 640, "height": 480}
    try:
        from sensor_msgs.msg import Image

        from symloc.msgs import build_rclpy
    except ImportError:
        print(
            "rclpy absent: rclpy message building skipped (pip install '.[ros]' in symloc's checkout)"
        )
        return out
    fields = image_to_fields(img, stamp=1.0)
    w, c = median_ms(lambda i: build_rclpy(Image, fields), repeats)
    print(f"Image 640x480, field dict -> rclpy msg:  {w:7.3f} ms wall  {c:7.3f} ms cpu")
    out["rclpy_image_from_fields"] = {"wall_ms": w, "cpu_ms": c, "width": 640, "height": 480}
    return out


def bench_node_logic(seed: int) -> dict[str, Any]:
    """NodeCore per scan over a recorded simulated kidnapped run: ms wall and CPU per scan."""
    from symloc.bench.sim_record import record_sim_run
    from symloc.ros.params import NodeParams
    from symloc.ros.replay import replay_bag

    d = Path(tempfile.mkdtemp(prefix="symloc-bench-ros-"))
    rec = record_sim_run(d / "run", seed=seed)
    params = NodeParams.from_yaml(rec.params_path)
    t0, c0 = time.perf_counter(), time.process_time()
    res = replay_bag(rec.bag, params)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    n = len(res.trajectory)
    print(
        f"NodeCore over a recorded kidnapped run:  {1e3 * wall / n:7.3f} ms wall  "
        f"{1e3 * cpu / n:7.3f} ms cpu per scan ({n} scans, 800 beams, 2000 particles max, "
        f"bag reading included)"
    )
    return {
        "wall_ms_per_scan": 1e3 * wall / n,
        "cpu_ms_per_scan": 1e3 * cpu / n,
        "scans": n,
        "beams": 800,
        "max_particles": 2000,
    }


def bench_dds(repeats: int) -> dict[str, Any]:
    """DDS loopback latency, publisher to subscriber in one process: ``{name: {"median_ms",
    "p90_ms", "delivered", "sent"}}`` (empty without rclpy)."""
    out: dict[str, Any] = {}
    try:
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import Image
        from sensor_msgs.msg import LaserScan as ScanMsg

        from symloc.msgs import build_rclpy
    except ImportError:
        print("rclpy absent: DDS round trips skipped (pip install '.[ros]' in symloc's checkout)")
        return out
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    ctx = Context()
    rclpy.init(context=ctx, domain_id=random.randint(150, 230))
    node = rclpy.create_node("bench_ros", context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    rng = np.random.default_rng(1)
    scan = LaserScan(-math.pi, 2 * math.pi / 800, 0.15, 12.0, rng.uniform(0.5, 6, 800), stamp=1.0)
    img = rng.integers(0, 256, (480, 640, 3), dtype=np.uint8)
    for key, name, cls, fields in (
        ("scan", "LaserScan 800 beams", ScanMsg, scan_to_fields(scan)),
        ("image", "Image 640x480 rgb8", Image, image_to_fields(img, stamp=1.0)),
    ):
        got: list[float] = []
        node.create_subscription(
            cls, f"bench_{cls.__name__}", lambda m, got=got: got.append(time.perf_counter()), 10
        )
        pub = node.create_publisher(cls, f"bench_{cls.__name__}", 10)
        msg = build_rclpy(cls, fields)
        end = time.monotonic() + 10
        while pub.get_subscription_count() < 1 and time.monotonic() < end:
            ex.spin_once(timeout_sec=0.05)
        lat = []
        for _ in range(repeats):
            n0 = len(got)
            t0 = time.perf_counter()
            pub.publish(msg)
            end = time.monotonic() + 5
            while len(got) == n0 and time.monotonic() < end:
                ex.spin_once(timeout_sec=0.01)
            if len(got) > n0:
                lat.append(got[-1] - t0)
        print(
            f"DDS loopback {name}: median {1e3 * float(np.median(lat)):.3f} ms,"
            f" p90 {1e3 * float(np.percentile(lat, 90)):.3f} ms ({len(lat)}/{repeats} delivered)"
        )
        out[key] = {
            "median_ms": 1e3 * float(np.median(lat)) if lat else None,
            "p90_ms": 1e3 * float(np.percentile(lat, 90)) if lat else None,
            "delivered": len(lat),
            "sent": repeats,
        }
    ex.shutdown()
    node.destroy_node()
    rclpy.shutdown(context=ctx)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0, help="seed of the recorded run (printed)")
    parser.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write a results file (the README's: docs/results/bench_ros.json) with the"
        " figures, command, commit, date, machine and load",
    )
    args = parser.parse_args()
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    print(f"# bench_ros  seed={args.seed}  repeats={args.repeats}")
    figures = {
        "conversions": bench_conversions(args.repeats),
        "node_logic": bench_node_logic(args.seed),
        "dds": bench_dds(args.repeats),
    }
    if args.results:
        from symloc.bench.results_file import write_run_results

        written = write_run_results(
            args.results,
            argv=sys.argv,
            clock=clock,
            settings={"repeats": args.repeats, "seed": args.seed},
            figures=figures,
            program="python",
        )
        print(f"wrote {written}")


if __name__ == "__main__":
    main()
