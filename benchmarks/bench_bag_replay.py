"""Benchmark: real CARMEN logs as ROS bags, end to end through the command line (issue 28).

For each log, as a user with a recording would run it:

1. ``symloc ros carmen-to-bag LOG --out DIR`` (scans, odometry, ground truth, an initial pose);
2. ``symloc map build --carmen LOG`` (the reference map and its ATE, printed by the command);
3. ``symloc replay BAG --map <that map> --params src/symloc/ros/examples/carmen_params.yaml``:
   the scans dropped (the command's ``dropped`` line) and the error of every scan's estimate
   (``replay_scans.tum``) against the log's corrected poses, both in the map frame as it is
   and after a 2-D rigid fit (a map built by SLAM has its own frame), over all scans and over
   the scans replay published as tracking (``replay.tum``);
4. ``symloc replay BAG --build-map``: the ATE of the trajectory SLAM wrote beside the map
   (``<map>_trajectory.tum``) against the corrected poses.

The issue's targets: replay's mean error within 0.02 m of ``symloc experiment amcl-carmen``'s
tracking error on the same log (run it beside: ``symloc experiment amcl-carmen --logs ...
--skip-global``), fewer than 1 % of scans dropped, ``--build-map`` within 0.02 m ATE of
``map build --carmen``. Rows are appended to ``<out>/bench_bag_replay.partial.jsonl`` as each
log finishes.

Run: ``python benchmarks/bench_bag_replay.py [--logs intel aces] [--out DIR]``
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from symloc.bench.shared_data import find_carmen_dir
from symloc.io.carmen import read_carmen

REPO = Path(__file__).resolve().parents[1]
PARAMS = REPO / "src" / "symloc" / "ros" / "examples" / "carmen_params.yaml"


def _run(cmd: list[str], log: Path) -> str:
    """Run a symloc command, keep its output in ``log``, return its standard output."""
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "symloc.cli.main", *cmd], capture_output=True, text=True
    )
    log.write_text(proc.stdout + "\n# stderr\n" + proc.stderr)
    print(f"#   {' '.join(cmd[:2])} ... exit {proc.returncode} in {time.perf_counter() - t0:.0f} s")
    if proc.returncode not in (0, 3):  # replay exits 3 when the recording was not usable
        raise RuntimeError(f"symloc {' '.join(cmd)} failed (exit {proc.returncode}); see {log}")
    return proc.stdout


def _tum(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Stamps (N,) and positions (N, 2) of a TUM file."""
    a = np.loadtxt(path, comments="#", ndmin=2)
    if a.size == 0:
        return np.zeros(0), np.zeros((0, 2))
    return a[:, 0], a[:, 1:3]


def _rigid(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """``src`` (N, 2) moved by the rigid transform that best fits it to ``dst`` (N, 2)."""
    ms, md = src.mean(0), dst.mean(0)
    u, _, vt = np.linalg.svd((src - ms).T @ (dst - md))
    r = vt.T @ u.T
    if np.linalg.det(r) < 0:
        vt[1] *= -1
        r = vt.T @ u.T
    return np.asarray((r @ (src - ms).T).T + md)


def _errors(tum: Path, stamps: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """Mean error [m] of the poses in ``tum`` against the reference at the nearest stamp."""
    t, xy = _tum(tum)
    if len(t) < 3:
        return {"n": len(t), "mean": float("nan"), "mean_aligned": float("nan")}
    idx = np.clip(np.searchsorted(stamps, t), 1, len(stamps) - 1)
    idx -= (t - stamps[idx - 1]) < (stamps[idx] - t)
    ref = truth[idx]
    raw = np.hypot(*(xy - ref).T)
    fit = np.hypot(*(_rigid(xy, ref) - ref).T)
    return {
        "n": len(t),
        "mean": float(raw.mean()),
        "mean_aligned": float(fit.mean()),
        "rmse_aligned": float(np.sqrt((fit**2).mean())),
    }


def bench_log(name: str, carmen: Path, out: Path) -> dict[str, Any]:
    """One log through the four commands (module docstring)."""
    log_path = carmen / f"{name}-corrected.log.gz"
    work = out / name
    work.mkdir(parents=True, exist_ok=True)
    data = read_carmen(log_path)
    stamps = np.array([s.stamp for s in data.scans])
    truth = np.array([s.laser_pose for s in data.scans])[:, :2]
    _run(["ros", "carmen-to-bag", str(log_path), "--out", str(work / "bag")], work / "bag.txt")
    bag = work / "bag" / f"{name}-corrected"
    built = _run(
        ["map", "build", "--carmen", str(log_path), "--out", str(work / "map")], work / "map.txt"
    )
    ate = re.search(r"ATE RMSE ([0-9.]+) m", built)
    replay = _run(
        [
            "replay", str(bag), "--map", str(work / "map" / "map.yaml"),
            "--params", str(PARAMS), "--out", str(work / "replay"),
        ],
        work / "replay.txt",
    )  # fmt: skip
    used = re.search(r"scans used: (\d+) of (\d+)", replay)
    bagmap = _run(
        [
            "replay",
            str(bag),
            "--build-map",
            str(work / "bagmap" / "map.yaml"),
            "--out",
            str(work / "bm"),
        ],
        work / "bagmap.txt",
    )
    del bagmap
    traj = work / "bagmap" / "map_trajectory.tum"
    row: dict[str, Any] = {
        "log": name,
        "scans": len(stamps),
        "scans_used": int(used.group(1)) if used else None,
        "dropped_share": (1.0 - int(used.group(1)) / int(used.group(2))) if used else None,
        "map_build_ate": float(ate.group(1)) if ate else None,
        "replay_all": _errors(work / "replay" / "replay_scans.tum", stamps, truth),
        "replay_tracked": _errors(work / "replay" / "replay.tum", stamps, truth),
        "build_map_ate": _errors(traj, stamps, truth).get("rmse_aligned")
        if traj.is_file()
        else None,
    }
    return row


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", nargs="+", default=["intel", "aces", "freiburg-079"])
    parser.add_argument("--carmen", type=Path, default=None, help="folder of the CARMEN logs")
    parser.add_argument("--out", type=Path, default=Path("bench_bag_replay_out"))
    args = parser.parse_args()
    carmen = args.carmen or find_carmen_dir()
    if carmen is None:
        print("no CARMEN logs: pass --carmen DIR or set SYMLOC_SHARED_DATA", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    partial = args.out / "bench_bag_replay.partial.jsonl"
    print(f"# bench_bag_replay: logs {args.logs} from {carmen}; replay params {PARAMS.name}")
    rows = []
    for name in args.logs:
        print(f"# {name}")
        row = bench_log(name, carmen, args.out)
        rows.append(row)
        with partial.open("a") as fh:
            fh.write(json.dumps(row) + "\n")
    print(
        f"\n{'log':<14}{'dropped':>9}{'replay mean (map frame / fitted) [m]':>40}"
        f"{'tracked mean [m]':>18}{'--build-map ATE':>17}{'map build ATE':>15}"
    )
    for r in rows:
        a, t = r["replay_all"], r["replay_tracked"]
        print(
            f"{r['log']:<14}{100 * (r['dropped_share'] or 0):>8.2f}%"
            f"{a['mean']:>28.3f} / {a['mean_aligned']:<9.3f}{t['mean']:>18.3f}"
            f"{r['build_map_ate'] or float('nan'):>17.3f}{r['map_build_ate'] or float('nan'):>15.3f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
