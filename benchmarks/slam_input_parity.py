"""What SLAM receives from ``map build --carmen`` and from ``replay --build-map`` (issue 28).

For each log and seed this builds SLAM's input on both paths, without running SLAM:

- ``map build --carmen LOG --seed N``: the log's scans as :func:`symloc.io.carmen.read_carmen`
  gives them and :func:`symloc.bench.slam_runs.map_build_odometry` (realistic, seed N);
- ``replay BAG --build-map``: the bag ``symloc ros carmen-to-bag LOG --odometry realistic
  --seed N`` writes (:func:`symloc.io.rosbag_carmen.carmen_to_bag` with that odometry), read
  back by :func:`symloc.ros.replay.pair_scans_offline` as ``--build-map`` reads it.

Each path's input then goes through :func:`symloc.slam.slam.slam_input` (what ``run_slam``
does to it first: odometry headings on a grid; the CARMEN reader already gives scans at the
bag's float32 precision), and every field SLAM could see is compared: the number and order of scans
(matched by stamp), ranges, beam angles, ``angle_min``/``angle_increment``, ``range_min``/
``range_max``, ``time_increment``/``scan_time``, stamps, frame and odometry. ``--raw`` compares
the inputs as each path hands them to ``run_slam`` (before :func:`slam_input`). It prints one
line per field with the number of scans that differ and the largest difference, and exits 1
when anything SLAM uses differs (stamps and frames are reported, SLAM does not read them).

Run: ``python benchmarks/slam_input_parity.py [--logs acapulco csail] [--seeds 0 1 2] [--raw]
[--dump DIR]`` (``--dump``: both paths' arrays as ``<log>_seed<N>_{carmen,bag}.npz``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from symloc.bench.shared_data import find_carmen_dir
from symloc.bench.slam_runs import map_build_odometry
from symloc.io.carmen import read_carmen
from symloc.io.rosbag_carmen import carmen_to_bag
from symloc.ros.replay import pair_scans_offline
from symloc.scan import LaserScan

#: Fields SLAM does not read (reported, not counted as a difference).
NOT_READ = ("stamp", "frame_id")


def arrays(scans: list[LaserScan], odometry: np.ndarray) -> dict[str, Any]:
    """The input of one path as arrays: per-scan scalars (N,), ranges and angles (N, beams)
    (beam counts are equal in the shared logs), odometry (N, 3)."""
    out: dict[str, Any] = {
        name: np.array([getattr(s, name) for s in scans], dtype=np.float64)
        for name in (
            "angle_min", "angle_increment", "range_min", "range_max", "time_increment",
            "scan_time", "stamp",
        )
    }  # fmt: skip
    out["ranges"] = np.stack([np.asarray(s.ranges) for s in scans])
    out["angles"] = np.stack([np.asarray(s.angles) for s in scans])
    out["frame_id"] = np.array([s.frame_id for s in scans])
    out["odometry"] = np.asarray(odometry, dtype=np.float64)
    return out


def compare(a: dict[str, Any], b: dict[str, Any]) -> tuple[list[str], bool]:
    """Lines describing each field's differences (``a`` CARMEN path, ``b`` bag path) and
    whether anything SLAM reads differs."""
    lines: list[str] = []
    differs = False
    for key in a:
        x, y = a[key], b[key]
        if x.shape != y.shape:
            lines.append(f"  {key:<16} shapes differ: {x.shape} vs {y.shape}")
            differs = differs or key not in NOT_READ
            continue
        same = (x == y) | (np.isnan(x) & np.isnan(y)) if x.dtype.kind in "fc" else x == y
        rows = ~same.reshape(len(x), -1).all(axis=1) if x.ndim else ~same
        n_rows = int(np.count_nonzero(rows))
        if n_rows == 0:
            lines.append(f"  {key:<16} identical (bit for bit)")
            continue
        differs = differs or key not in NOT_READ
        if x.dtype.kind in "fc":
            with np.errstate(invalid="ignore"):
                d = np.abs(x - y)
            big = float(np.nanmax(np.where(same, 0.0, d)))
            lines.append(
                f"  {key:<16} {n_rows} of {len(x)} scans differ in {int((~same).sum())} values,"
                f" max |difference| {big:.3g}" + ("  (not read by SLAM)" if key in NOT_READ else "")
            )
        else:
            lines.append(f"  {key:<16} {n_rows} of {len(x)} scans differ")
    return lines, differs


def both_paths(
    log_path: Path, name: str, seed: int, work: Path, *, raw: bool
) -> tuple[dict[str, Any], dict[str, Any], dict[str, int], int]:
    """SLAM's input on the CARMEN path and on the bag path, the bag path's dropped scans and
    the log's number of scans."""
    log = read_carmen(log_path)
    odom = map_build_odometry(log, name, "realistic", seed)
    carmen_scans = [s.scan for s in log.scans]
    bag = work / f"{name}-seed{seed}"
    carmen_to_bag(log_path, bag, odometry=odom, notes=[])
    got = pair_scans_offline(bag)
    bag_scans, bag_odom = list(got.scans), got.laser_odometry
    if not raw:
        from symloc.slam.slam import slam_input

        carmen_scans, odom = slam_input(carmen_scans, odom)
        bag_scans, bag_odom = slam_input(bag_scans, bag_odom)
    return arrays(carmen_scans, odom), arrays(bag_scans, bag_odom), got.dropped, len(log.scans)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", nargs="+", default=["acapulco", "csail"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument("--carmen", type=Path, default=None)
    parser.add_argument("--raw", action="store_true", help="before slam_input (as handed over)")
    parser.add_argument("--dump", type=Path, default=None, help="write both paths' arrays here")
    args = parser.parse_args()
    carmen = args.carmen or find_carmen_dir()
    if carmen is None:
        print("no CARMEN logs: pass --carmen DIR or set SYMLOC_SHARED_DATA", file=sys.stderr)
        return 2
    any_differs = False
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.logs:
            for seed in args.seeds:
                a, b, dropped, n = both_paths(
                    carmen / f"{name}-corrected.log.gz", name, seed, Path(tmp), raw=args.raw
                )
                lines, differs = compare(a, b)
                any_differs = any_differs or differs
                print(
                    f"{name} seed {seed}: {n} scans in the log; SLAM input"
                    f" {'(raw) ' if args.raw else ''}{'DIFFERS' if differs else 'identical'};"
                    f" bag path dropped {dropped or 'none'}",
                    flush=True,
                )
                print("\n".join(lines), flush=True)
                if args.dump is not None:
                    args.dump.mkdir(parents=True, exist_ok=True)
                    np.savez(args.dump / f"{name}_seed{seed}_carmen.npz", **a)
                    np.savez(args.dump / f"{name}_seed{seed}_bag.npz", **b)
    return 1 if any_differs else 0


if __name__ == "__main__":
    sys.exit(main())
