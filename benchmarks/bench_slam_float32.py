"""Benchmark: SLAM on a log's scans as read, as a bag holds them, and moved by 1e-7 (issue 28, 29).

A ROS bag stores a LaserScan's ranges and angles as float32; ``map build --carmen`` used to
read the log's text as float64, and that rounding alone flipped loop-closure decisions
(acapulco, seed 0: 0.158 m and 86 loop closures from float64, 0.250 m, 82, DOUBTFUL from
float32). The CARMEN reader now gives float32 scans (:func:`symloc.scan.message_precision`).
This runs SLAM on one log with the odometry ``map build --carmen --seed N`` gives it:

- ``as read``: the log's scans as :func:`symloc.io.carmen.read_carmen` gives them;
- ``as in a bag``: the same scans rounded to float32 as a bag holds them (ranges,
  ``angle_min``, ``angle_increment``, range limits): the same result as ``as read``, bit for
  bit, since the reader rounds alike;
- ``+1 ulp``: every finite range moved up by one float32 step (2^-24 of itself, 0.06-3 um):
  a perturbation that survives the rounding, of the size the rounding used to make. Its ATE
  against ``as read`` is SLAM's own sensitivity to the last digit of its input (issue 29's
  territory: how much of a single run's ATE is one draw from a spread).

It prints each run's ATE (RMSE after a rigid fit against the corrected poses), SLAM's verdict
(loop closures accepted, doubtful) and the +1 ulp run's ATE minus the as-read one.

Run: ``python benchmarks/bench_slam_float32.py [--logs acapulco csail] [--seed N] [--skip-bag]``
"""

from __future__ import annotations

import argparse
import sys
import time

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


def one_ulp_up(scan: LaserScan) -> LaserScan:
    """``scan`` at float32 precision with every finite range one float32 step larger."""
    r32 = np.asarray(scan.ranges, dtype=np.float32)
    up = np.where(np.isfinite(r32), np.nextafter(r32, np.float32(np.inf)), r32)
    return as_in_a_bag(scan).with_ranges(up.astype(np.float64))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", nargs="+", default=["acapulco", "csail"])
    parser.add_argument("--seed", type=int, default=0, help="map build --carmen's seed")
    parser.add_argument(
        "--skip-bag", action="store_true", help="skip the 'as in a bag' run (one SLAM run less)"
    )
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
        runs = [("as read", scans), ("+1 ulp", [one_ulp_up(s) for s in scans])]
        if not args.skip_bag:
            runs.insert(1, ("as in a bag", [as_in_a_bag(s) for s in scans]))
        ates = {}
        for label, given in runs:
            t0 = time.perf_counter()
            res = run_slam(given, odom, None, progress=False)
            verdict = "DOUBTFUL" if res.doubtful else "consistent"
            ates[label] = ate(log.laser_poses, res.poses).rmse
            print(
                f"{name:<14}{label:>14}{ates[label]:>9.3f}{len(res.loop_closures):>7}  {verdict}"
                f"  ({time.perf_counter() - t0:.0f} s)",
                flush=True,
            )
        print(f"{name:<14}{'+1 ulp - as read':>14}{ates['+1 ulp'] - ates['as read']:>+9.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
