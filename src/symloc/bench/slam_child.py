"""One symloc SLAM run in its own process, for :mod:`symloc.bench.slam_bench`.

``python -m symloc.bench.slam_child --log LOG --odometry ODO.npy --out RESULT.npz
[--max-scans N]`` reads the log, runs :func:`symloc.slam.run_slam` with the default
:class:`~symloc.slam.SlamParams` on its scans and the given odometry (N, 3), and writes
``poses`` (N, 3) and ``summary`` (a JSON string: loop closures accepted and rejected, the
result's warnings, CPU time of the SLAM itself) to ``RESULT.npz``. It runs in a fresh process
so that its peak memory (measured by :func:`symloc.bench.measure.run_measured`) is this run's.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from symloc.files.atomic import atomic_path

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit code."""
    parser = argparse.ArgumentParser(prog="python -m symloc.bench.slam_child")
    parser.add_argument("--log", type=Path, required=True)
    parser.add_argument("--odometry", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--max-scans", type=int, default=None)
    args = parser.parse_args(argv)

    from symloc.io.carmen import CarmenScan, iter_carmen
    from symloc.slam.slam import run_slam

    scans = []
    for msg in iter_carmen(args.log):
        if isinstance(msg, CarmenScan):
            scans.append(msg.scan)
            if args.max_scans is not None and len(scans) >= args.max_scans:
                break
    odom = np.load(args.odometry)
    result = run_slam(scans, odom, progress=False)
    summary = result.summary()
    with atomic_path(args.out) as tmp:
        np.savez(tmp, poses=result.poses, summary=json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
