"""Benchmark: how much of ``--build-map``'s ATE against ``map build --carmen`` is the bag's float32.

A ROS bag stores a LaserScan's ranges and angles as float32; ``map build --carmen`` reads the
log's text as float64. With the same odometry (``carmen-to-bag --odometry realistic --seed N``)
that rounding is all that differs between the two paths (issue 28). This runs SLAM on one log
twice with the odometry ``map build --carmen --seed N`` gives it: on the log's scans as read, and
on the same scans rounded to float32 as a bag holds them (ranges, ``angle_min``,
``angle_increment``), and prints both ATEs (RMSE after a rigid fit against the corrected poses)
and SLAM's verdict (loop closures accepted, doubtful).

Run: ``python benchmarks/bench_slam_float32.py [--logs acapulco csail] [--seed N]``
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from symloc.bench.shared_data import find_carmen_dir
from symloc.bench.slam_metrics import ate
from symloc.bench.slam_runs import map_build_odometry
from symloc.io.carmen import read_carmen
from symloc.scan import LaserScan
from symloc.slam.slam import run_slam


def as_in_a_bag(scan: LaserScan) -> LaserScan:
    """``scan`` with its ranges and angles rounded to float32, as a bag's LaserScan holds them."""
    return LaserScan(
        angle_min=float(np.float32(scan.angle_min)),
        angle_increment=float(np.float32(scan.angle_increment)),
        range_min=float(np.float32(scan.range_min)),
        range_max=float(np.float32(scan.range_max)),
        ranges=np.asarray(scan.ranges, dtype=np.float32).astype(np.float64),
        stamp=scan.stamp,
        frame_id=scan.frame_id,
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", nargs="+", default=["acapulco", "csail"])
    parser.add_argument("--seed", type=int, default=0, help="map build --carmen's seed")
    args = parser.parse_args()
    carmen = find_carmen_dir()
    if carmen is None:
        print("no CARMEN logs: set SYMLOC_SHARED_DATA", file=sys.stderr)
        return 2
    print(f"{'log':<14}{'scans':>14}{'ATE [m]':>9}{'loops':>7}  verdict")
    for name in args.logs:
        log = read_carmen(carmen / f"{name}-corrected.log.gz")
        odom = map_build_odometry(log, name, "realistic", args.seed)
        scans = [s.scan for s in log.scans]
        for label, given in (("float64", scans), ("float32", [as_in_a_bag(s) for s in scans])):
            res = run_slam(given, odom, None, progress=False)
            verdict = "DOUBTFUL" if res.doubtful else "consistent"
            print(
                f"{name:<14}{label:>14}{ate(log.laser_poses, res.poses).rmse:>9.3f}"
                f"{len(res.loop_closures):>7}  {verdict}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
