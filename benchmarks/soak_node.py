"""Soak test of the node logic: 30 minutes at 10 Hz with 1 % malformed messages (not in CI).

    python benchmarks/soak_node.py [--minutes 30] [--rate 10] [--malformed 0.01] [--seed 0]
                                   [--map-change 10] [--json soak.json] [--results PATH]

A robot circles in an L-shaped room (simulated RPLIDAR A2 scans, exact odometry at 5x the scan
rate, a camera image every second that nobody asked for) and :class:`symloc.ros.core.NodeCore`
with the real localizer (nav2 AMCL defaults) runs on the messages, paced in real time. A share
of the messages is replaced by a malformed one drawn from a fixed catalogue (NaN or absurd
odometry, odometry from the future, clock jumps, scans of the wrong length or with NaN fields,
image bombs, unknown encodings, initial poses outside the map, maps with no free cell).
With ``--map-change S`` a new map arrives on the map topic every S seconds of simulated time
(the same room with a 2 x 2-cell box somewhere else, as in ``map_change_memory.py``), so the
localizer is rebuilt on it (issue 31: "a 30-minute soak with a map change every 10 s").

Prints, per 5-minute window: scans, statuses, tracked scans, latency p50 / p99 of the scan
handling [ms] and the process RSS [MB], and a line ``rss`` every minute; with ``--json`` the
file is rewritten after every window, so a run that is stopped leaves its partial results. Then
the verdicts: RSS flat within 10 % of the median after the first minute's warm-up, RSS within
5 % of its level at the first minute (issue 31's criterion), p99 stable (the last window within
1.5x the first), a status for every scan, and the drop and recovery counters. ``--results
PATH`` also writes them as a results file (the README's: ``docs/results/soak_node.json``:
the windows as rows, the verdicts, command, commit, date, machine and load).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np


def rss_mb() -> float:
    """Current resident set size [MB] (Linux /proc)."""
    with open(f"/proc/{os.getpid()}/statm") as fh:
        pages = int(fh.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--rate", type=float, default=10.0, help="scans per second")
    ap.add_argument("--malformed", type=float, default=0.01, help="share of messages")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--window", type=float, default=5.0, help="report window [min]")
    ap.add_argument(
        "--map-change",
        type=float,
        default=0.0,
        help="a new map on the map topic every this many seconds (0: never)",
    )
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write a results file (the README's: docs/results/soak_node.json)",
    )
    args = ap.parse_args(argv)
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from rosbags.typesys import Stores, get_typestore

    from map_change_memory import moved_box_map
    from symloc.grid import OccupancyGrid
    from symloc.msgs import (
        build_rosbags,
        compressed_image_to_fields,
        grid_to_fields,
        odometry_to_fields,
        pose_with_covariance_to_fields,
        scan_to_fields,
    )
    from symloc.odometry import OdometryReading
    from symloc.ros.core import NodeCore
    from symloc.ros.params import NodeParams
    from symloc.sim.lidar import PRESETS, simulate_scan
    from symloc.sim.rasterize import world_to_grid
    from symloc.sim.rooms import build_room

    ts = get_typestore(Stores.ROS2_HUMBLE)
    rng = np.random.default_rng(args.seed)
    room = build_room("l_shaped", 3.0, lab=False)
    grid = world_to_grid(room.world, 0.05)
    preset = PRESETS["rplidar_a2"]
    centre = np.asarray(room.center, float)
    t0 = 1_700_000_000.0  # a wall-clock-like time base

    def truth(t: float) -> np.ndarray:
        a = 0.2 * (t - t0)
        return np.array(
            [centre[0] + 0.4 * math.cos(a), centre[1] + 0.4 * math.sin(a), a + math.pi / 2]
        )

    def msg(kind: str, fields: dict[str, Any]) -> Any:
        return build_rosbags(ts, kind, fields)

    def odom(t: float, pose: Any = None) -> Any:
        p = truth(t) if pose is None else np.asarray(pose, float)
        return msg("nav_msgs/msg/Odometry", odometry_to_fields(OdometryReading(p, t)))

    def scan_fields(t: float) -> dict[str, Any]:
        s = simulate_scan(room.world, truth(t), preset, rng, stamp=t, frame_id="laser")
        return scan_to_fields(s)

    camera = np.asarray(rng.integers(0, 255, (480, 640, 3)), np.uint8)
    camera_msg = msg(
        "sensor_msgs/msg/CompressedImage",
        compressed_image_to_fields(camera, stamp=t0, frame_id="camera", fmt="jpeg"),
    )

    def bad(t: float) -> tuple[str, Any]:
        """One malformed message from the catalogue."""
        k = int(rng.integers(0, 12))
        if k == 0:
            f = odometry_to_fields(OdometryReading(truth(t), t))
            f["pose"]["pose"]["position"]["x"] = float("nan")
            return "odom", msg("nav_msgs/msg/Odometry", f)
        if k == 1:
            return "odom", odom(t + 20.0)
        if k == 2:
            return "odom", odom(t, [1e300, 1e154, 0.0])
        if k == 3:
            return "odom", odom(t - 5.0)
        if k == 4:
            f = scan_fields(t)
            f["ranges"] = np.asarray(f["ranges"])[:-7]
            return "scan", msg("sensor_msgs/msg/LaserScan", f)
        if k == 5:
            f = scan_fields(t)
            f["angle_increment"] = float("nan")
            return "scan", msg("sensor_msgs/msg/LaserScan", f)
        if k == 6:
            f = scan_fields(t + 1e6)
            return "scan", msg("sensor_msgs/msg/LaserScan", f)
        if k == 7:
            header = {"stamp": {"sec": int(t), "nanosec": 0}, "frame_id": "camera"}
            ihdr = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + (16000).to_bytes(4, "big") * 2
            data = np.frombuffer(ihdr + b"\x08\x02\x00\x00\x00" + bytes(300), np.uint8)
            return "cimage", msg(
                "sensor_msgs/msg/CompressedImage",
                {"header": header, "format": "png", "data": data},
            )
        if k == 8:
            header = {"stamp": {"sec": int(t), "nanosec": 0}, "frame_id": "camera"}
            f = {
                "header": header,
                "height": 4,
                "width": 4,
                "encoding": "yuv422",
                "is_bigendian": 0,
                "step": 8,
                "data": np.zeros(32, np.uint8),
            }
            return "image", msg("sensor_msgs/msg/Image", f)
        if k == 9:
            f = pose_with_covariance_to_fields([1e154, 0.0, 0.0], np.eye(3), stamp=t)
            return "initialpose", msg("geometry_msgs/msg/PoseWithCovarianceStamped", f)
        if k == 10:
            walls = OccupancyGrid(np.full((30, 30), 100, np.int8), 0.05)
            return "map", msg("nav_msgs/msg/OccupancyGrid", grid_to_fields(walls, stamp=t))
        # a clock jump of scan and odometry, once
        return "odom", odom(t + 3600.0)

    core = NodeCore(NodeParams(laser_frame_id="laser"))
    handlers = {
        "scan": core.on_scan,
        "odom": core.on_odom,
        "map": core.on_map,
        "image": core.on_image,
        "cimage": core.on_compressed_image,
        "initialpose": core.on_initialpose,
    }
    core.on_map(msg("nav_msgs/msg/OccupancyGrid", grid_to_fields(grid, stamp=t0)))
    core.on_odom(odom(t0))
    f = pose_with_covariance_to_fields(truth(t0), np.diag([0.01, 0.01, 0.01]), stamp=t0)
    core.on_initialpose(msg("geometry_msgs/msg/PoseWithCovarianceStamped", f))

    period = 1.0 / args.rate
    n_scans = int(args.minutes * 60.0 * args.rate)
    per_window = int(args.window * 60.0 * args.rate)
    per_map = round(args.map_change * args.rate) if args.map_change > 0 else 0
    maps_sent = 0
    rows: list[dict[str, Any]] = []
    lat: list[float] = []
    window = Counter()
    rss: list[tuple[float, float]] = []
    sent = Counter()
    malformed = Counter()
    start = time.monotonic()
    print(
        f"# soak: {args.minutes:g} min at {args.rate:g} Hz ({n_scans} scans), "
        f"{100 * args.malformed:g} % malformed, seed {args.seed}, pid {os.getpid()}, "
        f"map change every {args.map_change:g} s",
        flush=True,
    )

    def send(kind: str, m: Any) -> Any:
        if rng.random() < args.malformed:
            kind, m = bad(t)
            malformed[kind] += 1
        sent[kind] += 1
        return kind, handlers[kind](m)

    for i in range(n_scans):
        t = t0 + (i + 1) * period
        for j in range(5):  # odometry at 5x the scan rate
            send("odom", odom(t - period + (j + 1) * period / 5))
        if i % int(args.rate) == 0:
            send("cimage", camera_msg)
        m = msg("sensor_msgs/msg/LaserScan", scan_fields(t))
        tick = time.perf_counter()
        kind, out = send("scan", m)
        took = time.perf_counter() - tick
        if kind == "scan":
            lat.append(took)
            window["scans"] += 1
            window["statuses"] += out is not None and bool(out.status)
            est = getattr(out, "estimate", None)
            if getattr(out, "used", False) and est is not None and est.pose is not None:
                window["tracked"] += 1
                err = float(np.hypot(*(est.pose[:2] - truth(t)[:2])))
                window["tracked_within_0.2m"] += err < 0.2
        if per_map and (i + 1) % per_map == 0:
            maps_sent += 1
            grid_k = moved_box_map(grid, maps_sent)
            core.on_map(msg("nav_msgs/msg/OccupancyGrid", grid_to_fields(grid_k, stamp=t)))
            if core.map_refused:
                print(f"# map {maps_sent} refused: {core.map_refused}", flush=True)
        if i % int(10 * args.rate) == 0:
            rss.append((time.monotonic() - start, rss_mb()))
            if i % int(60 * args.rate) == 0:
                print(
                    json.dumps(
                        {"rss": round(rss[-1][1], 1), "s": round(rss[-1][0], 1), "maps": maps_sent}
                    ),
                    flush=True,
                )
        if (i + 1) % per_window == 0 or i + 1 == n_scans:
            a = np.array(lat) * 1000.0
            row = {
                "minute": round((i + 1) / args.rate / 60.0, 2),
                **window,
                "latency_p50_ms": round(float(np.percentile(a, 50)), 2),
                "latency_p99_ms": round(float(np.percentile(a, 99)), 2),
                "rss_mb": round(rss_mb(), 1),
            }
            rows.append(row)
            print(json.dumps(row), flush=True)
            lat.clear()
            window = Counter()
            if args.json is not None:
                partial = {"windows": rows, "rss_mb": rss, "maps_sent": maps_sent, "partial": True}
                args.json.write_text(json.dumps(partial, indent=2) + "\n")
        sleep = start + (i + 1) * period - time.monotonic()
        if sleep > 0:
            time.sleep(sleep)

    warm = [r for s, r in rss if s >= 60.0] or [r for _, r in rss]
    med = float(np.median(warm))
    spread = max(abs(r - med) for r in warm) / med
    at_1min = warm[0]
    from_1min = max(abs(r - at_1min) for r in warm) / at_1min
    p99 = [r["latency_p99_ms"] for r in rows]
    scans = sum(r.get("scans", 0) for r in rows)
    statuses = sum(r.get("statuses", 0) for r in rows)
    verdict = {
        "rss_mb_first_last": [round(warm[0], 1), round(warm[-1], 1)],
        "rss_mb_median_after_1min": round(med, 1),
        "rss_max_deviation_from_median": round(spread, 4),
        "rss_flat_within_10pct": spread <= 0.10,
        "rss_mb_at_1min_max_end": [round(at_1min, 1), round(max(warm), 1), round(warm[-1], 1)],
        "rss_max_deviation_from_1min": round(from_1min, 4),
        "rss_within_5pct_of_1min": from_1min <= 0.05,
        "maps_sent": maps_sent,
        "latency_p99_ms_first_last_window": [p99[0], p99[-1]],
        "latency_p99_stable": p99[-1] <= 1.5 * p99[0],
        "scans": scans,
        "statuses": statuses,
        "status_every_scan": scans == statuses,
        "tracked_scans": sum(r.get("tracked", 0) for r in rows),
        "tracked_within_0.2m": sum(r.get("tracked_within_0.2m", 0) for r in rows),
        "messages_sent": dict(sent),
        "malformed_sent": dict(malformed),
        "dropped": dict(core.dropped),
        "recovered": dict(core.recovered),
        "wall_minutes": round((time.monotonic() - start) / 60.0, 2),
        "load_average": os.getloadavg(),
    }
    print(json.dumps(verdict, indent=2))
    if args.json is not None:
        final = {"windows": rows, "rss_mb": rss, "verdict": verdict}
        args.json.write_text(json.dumps(final, indent=2) + "\n")
    if args.results is not None:
        from symloc.bench.results_file import write_bench_results

        settings = {
            k: getattr(args, k)
            for k in ("minutes", "rate", "malformed", "seed", "window", "map_change")
        }
        written = write_bench_results(
            args.results,
            clock=clock,
            settings=settings,
            figures={"rows": rows, "verdict": verdict, "rss_mb": [list(x) for x in rss]},
            argv=sys.argv if argv is None else [sys.argv[0], *argv],
        )
        print(f"wrote {written}")
    ok = verdict["rss_flat_within_10pct"] and verdict["status_every_scan"]
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
