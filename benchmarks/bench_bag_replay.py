"""Benchmark: real CARMEN logs as ROS bags, end to end through the command line (issue 28).

For each log, as a user with a recording would run it:

1. ``symloc ros carmen-to-bag LOG --out DIR`` (scans, odometry, ground truth, an initial pose);
2. ``symloc map build --carmen LOG --seed N`` (the reference map and its ATE, printed by the
   command; SLAM on the log's scans with the "realistic" odometry noise drawn from seed N);
3. ``symloc replay BAG --map <that map> --params src/symloc/ros/examples/carmen_params.yaml``:
   the scans dropped (the command's ``dropped`` line) and the error of every scan's estimate
   (``replay_scans.tum``) against the log's corrected poses, both in the map frame as it is
   and after a 2-D rigid fit (a map built by SLAM has its own frame), over all scans and over
   the scans replay published as tracking (``replay.tum``);
4. ``symloc replay BAG --build-map``: the ATE of the trajectory SLAM wrote beside the map
   (``<map>_trajectory.tum``) against the corrected poses. This bag's odometry is the log's own
   (the corrected poses, perfect odometry), not what step 2 maps with, so the two ATEs differ
   by their input; for the issue's comparison:
7. ``symloc ros carmen-to-bag LOG --odometry realistic --seed N``: a bag with step 2's odometry,
   and ``symloc replay`` of it ``--build-map``: its ATE against step 2's (same log, scans and
   odometry; SLAM's input is the same bit for bit on both paths since the CARMEN reader gives
   scans at sensor_msgs/LaserScan's float32 precision, :func:`symloc.slam.slam.slam_input`
   rounds odometry headings to a grid finer than 1e-9 rad, and the bag stamps intel's four
   backward scans after their predecessors; ``python benchmarks/slam_input_parity.py``
   compares the two inputs).

Step 3 is not the experiment the issue compares with: its map is SLAM's (its own error, an
ATE of several centimetres, is in every pose measured against the corrected poses) and the
corrected logs' odometry is the corrected poses themselves (perfect odometry), where ``symloc
experiment amcl-carmen`` tracks on a map drawn from the corrected poses with odometry it makes
noisy (alpha1..4 = 0.01). So, for the issue's comparison, on the same map and odometry:

5. ``symloc experiment amcl-carmen --logs LOG --skip-global --seed N``: its tracking error
   (every scan, the filter's pose carried by odometry between updates) and its map; then its
   AMCL again in this process (:func:`symloc.experiments.amcl_carmen.amcl_tracking_error`: the
   same odometry draw and random stream) as run, updating on every scan, and with alpha1 0.04
   (:data:`AMCL_VARIANTS`), to tell why a log where it loses track does;
6. ``symloc ros carmen-to-bag LOG --odom-alpha 0.01 --seed N``: a bag with that experiment's
   odometry, replayed with ``carmen_params.yaml`` on the experiment's map (written as a map
   file): the mean error of every scan's estimate against the corrected poses in the map
   frame (the experiment's frame; no fit), its difference from the experiment's, and the
   scans dropped.

The issue's targets: replay's mean error within 0.02 m of ``symloc experiment amcl-carmen``'s
tracking error on the same log (step 6 against step 5), fewer than 1 % of scans dropped,
``--build-map`` within 0.02 m ATE of ``map build --carmen``. Replay poses are matched to the
bag's ground truth (the corrected poses) by their stamps, in order among repeated stamps (intel's
go backwards now and then; a log without usable stamps is stamped by its motion in the bag).
Rows are appended to ``<out>/bench_bag_replay.partial.jsonl`` (emptied when the run starts) as
each log finishes, and a line of progress printed.
``--results PATH`` writes, at the end, a results file (:mod:`symloc.bench.bag_replay_results`:
per log the figures above, the scans dropped with their reasons, and the run's command, commit,
date, machine and load); README.md renders its paragraph from
``docs/results/bench_bag_replay.json`` (``python -m symloc.readme``).

Run: ``python benchmarks/bench_bag_replay.py [--logs intel aces] [--out DIR] [--seeds N ...]
[--build-map-only] [--no-own-odometry] [--results PATH]`` (several seeds: every log with the
first seed, then with the next; a seed other than 0 works in ``<out>/<log>_seed<N>``).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from symloc.bench.bag_replay_results import replay_counts, write_bag_replay_results
from symloc.bench.provenance import RunClock
from symloc.bench.shared_data import find_carmen_dir

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


def _reference_index(stamps: np.ndarray, t: np.ndarray) -> np.ndarray:
    """For each stamp of ``t`` (in replay order) the index of the log's scan it belongs to:
    the next scan not yet taken with that exact stamp (TUM keeps 9 decimals), else the scan of
    the nearest stamp. ``stamps`` may go backwards or repeat (a log's own clock)."""
    queues: dict[float, list[int]] = {}
    for i, s in enumerate(np.round(stamps, 6).tolist()):
        queues.setdefault(s, []).append(i)
    order = np.argsort(stamps, kind="stable")
    ordered = stamps[order]
    out = np.empty(len(t), dtype=np.int64)
    for k, tk in enumerate(np.round(t, 6).tolist()):
        q = queues.get(tk)
        if q:
            out[k] = q.pop(0)
            continue
        j = int(np.clip(np.searchsorted(ordered, tk), 1, len(ordered) - 1))
        j -= (tk - ordered[j - 1]) < (ordered[j] - tk)
        out[k] = order[j]
    return out


def _errors(tum: Path, stamps: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """Mean error [m] of the poses in ``tum`` against the reference at their scans
    (:func:`_reference_index`), as they are and after a rigid fit."""
    t, xy = _tum(tum)
    if len(t) < 3:
        return {"n": len(t), "mean": float("nan"), "mean_aligned": float("nan")}
    ref = truth[_reference_index(stamps, t)]
    raw = np.hypot(*(xy - ref).T)
    fit = np.hypot(*(_rigid(xy, ref) - ref).T)
    return {
        "n": len(t),
        "mean": float(raw.mean()),
        "mean_aligned": float(fit.mean()),
        "rmse_aligned": float(np.sqrt((fit**2).mean())),
    }


def _bag_poses(bag: Path) -> tuple[np.ndarray, np.ndarray]:
    """The bag's ground truth (the log's corrected poses as carmen-to-bag wrote them): stamps
    (N,) [s] and poses (N, 3) [m, m, rad]. Its stamps are the bag's, the ones replay writes (a
    log without usable stamps is stamped by its motion in the bag)."""
    from symloc.io.rosbag import read_bag

    msgs = [m for m in read_bag(bag, kinds=("truth",)) if m.kind == "truth"]
    stamps = np.array([m.stamp for m in msgs], dtype=np.float64)
    poses = np.array([m.value.pose[:3] for m in msgs], dtype=np.float64).reshape(-1, 3)
    return stamps, poses


def _bag_reference(bag: Path) -> tuple[np.ndarray, np.ndarray]:
    """The bag's ground truth: stamps (N,) [s] and positions (N, 2) [m] (:func:`_bag_poses`)."""
    stamps, poses = _bag_poses(bag)
    return stamps, poses[:, :2]


def _heading_variance(a: np.ndarray, b: np.ndarray, alpha: float) -> np.ndarray:
    """The variance [rad^2] of the heading change ``rot1 + rot2`` that the rot-trans-rot model
    with alpha1..4 = ``alpha`` gives the motions from poses ``a`` to ``b`` (..., 3)."""
    from symloc.odometry import rot_trans_rot

    r1, tr, r2 = rot_trans_rot(a, b)
    q1 = np.minimum(np.abs(r1), np.pi - np.abs(r1))
    q2 = np.minimum(np.abs(r2), np.pi - np.abs(r2))
    return np.asarray(alpha * (q1**2 + q2**2) + 2 * alpha * tr**2)


def _motion(poses: np.ndarray, alpha: float = 0.01) -> dict[str, float]:
    """The scan-to-scan motions of the corrected poses (N, 3) as the odometry noise of
    ``experiment amcl-carmen`` splits them (rot-trans-rot, no first rotation below 1 cm): the
    share whose first rotation exceeds 0.5 rad and the median step [m]; and, over the motions
    AMCL integrates at once (it updates after 0.25 m or 0.2 rad, nav2's defaults, here on the
    corrected poses rather than the noisy odometry), the share of updates whose heading noise,
    drawn scan by scan, has more than twice the standard deviation AMCL's model gives the
    update's motion as one (both with alpha1..4 = ``alpha``)."""
    from symloc.geometry import angle_diff
    from symloc.odometry import rot_trans_rot

    nan = float("nan")
    if len(poses) < 2:
        return {
            "rot1_over_half_rad_share": nan,
            "median_step_m": nan,
            "updates": 0,
            "heading_noise_over_twice_model_share": nan,
        }
    rot1, trans, _ = rot_trans_rot(poses[:-1], poses[1:])
    per_scan = _heading_variance(poses[:-1], poses[1:], alpha)
    drawn, model = [], []
    last = 0
    for i in range(1, len(poses)):
        moved = np.hypot(*(poses[i, :2] - poses[last, :2]))
        turned = abs(float(angle_diff(poses[i, 2], poses[last, 2])))
        if moved >= 0.25 or turned >= 0.2:
            drawn.append(per_scan[last:i].sum())
            model.append(float(_heading_variance(poses[last], poses[i], alpha)))
            last = i
    wide = np.sqrt(drawn) > 2 * np.sqrt(model) if drawn else np.zeros(0, dtype=bool)
    return {
        "rot1_over_half_rad_share": float((np.abs(rot1) > 0.5).mean()),
        "median_step_m": float(np.median(trans)),
        "updates": len(drawn),
        "heading_noise_over_twice_model_share": float(wide.mean()) if len(wide) else nan,
    }


#: AMCL alone on the experiment's map and odometry with one parameter changed
#: (:func:`symloc.experiments.amcl_carmen.amcl_tracking_error`): as the experiment runs it,
#: updating on every scan, and with its rotational noise alpha1 four times wider (0.04).
AMCL_VARIANTS: dict[str, dict[str, float]] = {
    "as_run": {},
    "every_scan": {"update_min_d": 0.0, "update_min_a": 0.0},
    "alpha1_0.04": {"alpha1": 0.04},
}


def amcl_variants(name: str, log_path: Path, map_cache: Path, seed: int) -> dict[str, Any]:
    """Step 5's AMCL again in this process, as run and with each change of
    :data:`AMCL_VARIANTS`: mean, median and largest error [m] of each."""
    from symloc.experiments.amcl_carmen import amcl_tracking_error, log_data

    data = log_data(name, log_path, cache=map_cache)
    return {k: amcl_tracking_error(data, seed, **v) for k, v in AMCL_VARIANTS.items()}


def _map_file(npz: Path, yaml: Path) -> Path:
    """The experiment's cached map (``amcl_carmen_map_<log>.npz``) as a map file, in raw mode
    (the grid round-trips exactly; trinary would turn cells between the thresholds unknown)."""
    from symloc.grid import OccupancyGrid
    from symloc.grid.map_io import save_map

    z = np.load(npz)
    grid = OccupancyGrid(z["data"], float(z["resolution"]), z["origin"])
    return save_map(grid, yaml, mode="raw")


def _dropped(replay_out: str) -> float | None:
    """The share of the bag's scans replay did not use (its ``scans used`` line)."""
    counts = replay_counts(replay_out)
    return None if counts is None else counts["dropped_share"]


def same_as_experiment(
    name: str, log_path: Path, carmen: Path, work: Path, seed: int
) -> dict[str, Any]:
    """Steps 5 and 6 of the module docstring: the experiment's tracking error and the replay's
    on the experiment's map and odometry."""
    _run(
        [
            "experiment", "amcl-carmen", "--logs", name, "--data", str(carmen), "--skip-global",
            "--seed", str(seed), "--out", str(work / "amcl"), "--json", str(work / "amcl.json"),
        ],
        work / "amcl.txt",
    )  # fmt: skip
    tracking = json.loads((work / "amcl.json").read_text())["logs"][0]["tracking"]
    map_yaml = _map_file(
        work / "amcl" / f"amcl_carmen_map_{name}.npz", work / "amclmap" / "map.yaml"
    )
    _run(
        [
            "ros", "carmen-to-bag", str(log_path), "--out", str(work / "bag_amcl"),
            "--odom-alpha", "0.01", "--seed", str(seed),
        ],
        work / "bag_amcl.txt",
    )  # fmt: skip
    replay = _run(
        [
            "replay", str(work / "bag_amcl" / f"{name}-corrected"), "--map", str(map_yaml),
            "--params", str(PARAMS), "--out", str(work / "replay_amcl"),
        ],
        work / "replay_amcl.txt",
    )  # fmt: skip
    stamps, truth = _bag_reference(work / "bag_amcl" / f"{name}-corrected")
    err = _errors(work / "replay_amcl" / "replay_scans.tum", stamps, truth)
    variants = amcl_variants(name, log_path, work / "amcl" / f"amcl_carmen_map_{name}.npz", seed)
    return {
        "amcl_carmen_mean": float(tracking["mean_error_m"]),
        "replay_mean": err["mean"],
        "replay_n": err["n"],
        "difference": err["mean"] - float(tracking["mean_error_m"]),
        "dropped_share": _dropped(replay),
        "dropped": replay_counts(replay),
        "amcl_variants": variants,
    }


def _build_map_ate(bag: Path, work: Path, tag: str) -> float | None:
    """``symloc replay BAG --build-map``: the ATE [m] (RMSE after a rigid fit) of the trajectory
    SLAM wrote beside the map against the bag's ground truth (the corrected poses)."""
    stamps, truth = _bag_reference(bag)
    _run(["replay", str(bag), "--build-map", str(work / tag / "map.yaml")], work / f"{tag}.txt")
    traj = work / tag / "map_trajectory.tum"
    return _errors(traj, stamps, truth).get("rmse_aligned") if traj.is_file() else None


def same_input_as_map_build(name: str, log_path: Path, work: Path, seed: int) -> dict[str, Any]:
    """Step 2 and 7 of the module docstring: ``map build --carmen LOG --seed N`` (its ATE as
    it prints it) and ``replay --build-map`` on a bag carrying the odometry that command maps
    with (``carmen-to-bag --odometry realistic --seed N``)."""
    built = _run(
        ["map", "build", "--carmen", str(log_path), "--seed", str(seed), "--out",
         str(work / "map")],
        work / "map.txt",
    )  # fmt: skip
    ate = re.search(r"ATE RMSE ([0-9.]+) m", built)
    _run(
        ["ros", "carmen-to-bag", str(log_path), "--out", str(work / "bag_mb"), "--odometry",
         "realistic", "--seed", str(seed)],
        work / "bag_mb.txt",
    )  # fmt: skip
    bm = _build_map_ate(work / "bag_mb" / f"{name}-corrected", work, "bagmap_mb")
    mb = float(ate.group(1)) if ate else None
    return {
        "map_build_ate": mb,
        "build_map_ate": bm,
        "difference": None if bm is None or mb is None else bm - mb,
    }


def bench_log(
    name: str,
    carmen: Path,
    out: Path,
    seed: int = 0,
    build_map_only: bool = False,
    own_odometry: bool = True,
) -> dict[str, Any]:
    """One log through the commands of the module docstring (``build_map_only``: steps 1, 2, 4
    and 7; without ``own_odometry`` step 4 is skipped, its ATE None)."""
    t0 = time.perf_counter()
    log_path = carmen / f"{name}-corrected.log.gz"
    work = out / (name if seed == 0 else f"{name}_seed{seed}")
    work.mkdir(parents=True, exist_ok=True)
    _run(["ros", "carmen-to-bag", str(log_path), "--out", str(work / "bag")], work / "bag.txt")
    bag = work / "bag" / f"{name}-corrected"
    stamps, poses = _bag_poses(bag)
    truth = poses[:, :2]
    same = same_input_as_map_build(name, log_path, work, seed)
    row: dict[str, Any] = {
        "log": name,
        "seed": seed,
        "scans": len(stamps),
        "map_build_ate": same["map_build_ate"],
        "build_map_ate": _build_map_ate(bag, work, "bagmap") if own_odometry else None,
        "same_input_as_map_build": same,
        "motion": _motion(poses),
    }
    if build_map_only:
        row["wall_s"] = time.perf_counter() - t0
        return row
    replay = _run(
        [
            "replay", str(bag), "--map", str(work / "map" / "map.yaml"),
            "--params", str(PARAMS), "--out", str(work / "replay"),
        ],
        work / "replay.txt",
    )  # fmt: skip
    row.update(
        dropped_share=_dropped(replay),
        dropped=replay_counts(replay),
        replay_all=_errors(work / "replay" / "replay_scans.tum", stamps, truth),
        replay_tracked=_errors(work / "replay" / "replay.tum", stamps, truth),
        same_as_experiment=same_as_experiment(name, log_path, carmen, work, seed),
        wall_s=time.perf_counter() - t0,
    )
    return row


def _progress(row: dict[str, Any]) -> str:
    """One line on a finished log: its wall time and the issue's comparison."""
    text = f"{row['log']} seed {row['seed']} done in {row['wall_s']:.0f} s"
    e = row.get("same_as_experiment")
    if e:
        d = e.get("dropped") or {}
        text += (
            f": replay {e['replay_mean']:.3f} m, experiment {e['amcl_carmen_mean']:.3f} m"
            f" ({e['difference']:+.3f}), dropped {d.get('dropped')} of {d.get('scans')}"
        )
    m = row["same_input_as_map_build"]
    if m.get("difference") is not None:
        text += f"; --build-map - map build ATE {m['difference']:+.4f} m"
    return text


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", nargs="+", default=["intel", "aces", "freiburg-079"])
    parser.add_argument("--carmen", type=Path, default=None, help="folder of the CARMEN logs")
    parser.add_argument("--out", type=Path, default=Path("bench_bag_replay_out"))
    parser.add_argument(
        "--seed",
        "--seeds",
        dest="seeds",
        type=int,
        nargs="+",
        default=[0],
        help="the odometry noise's seed(s): of experiment amcl-carmen and of map build --carmen"
        " (several: every log with each, seed by seed)",
    )
    parser.add_argument(
        "--build-map-only",
        action="store_true",
        help="only --build-map against map build --carmen (steps 1, 2, 4, 7)",
    )
    parser.add_argument(
        "--no-own-odometry",
        action="store_true",
        help="skip step 4 (--build-map on the log's own odometry; one SLAM run per log less)",
    )
    parser.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write a results file (the README's: docs/results/bench_bag_replay.json) with"
        " per log the replay's and the experiment's mean error, their difference, the scans"
        " dropped, and the command, commit, date, machine and load; python -m symloc.readme"
        " re-renders the README from it",
    )
    args = parser.parse_args()
    clock = RunClock()
    carmen = args.carmen or find_carmen_dir()
    if carmen is None:
        print("no CARMEN logs: pass --carmen DIR or set SYMLOC_SHARED_DATA", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    partial = args.out / "bench_bag_replay.partial.jsonl"
    partial.write_text("")  # this run's rows only (a rerun into the same --out starts afresh)
    print(
        f"# bench_bag_replay: logs {args.logs} from {carmen}; replay params {PARAMS.name};"
        f" rows appended to {partial} as each log finishes",
        flush=True,
    )
    rows = []
    runs = [(seed, name) for seed in args.seeds for name in args.logs]
    for k, (seed, name) in enumerate(runs, 1):
        print(f"# [{k}/{len(runs)}] {name} seed {seed} (load {os.getloadavg()[0]:.2f})", flush=True)
        row = bench_log(name, carmen, args.out, seed, args.build_map_only, not args.no_own_odometry)
        rows.append(row)
        with partial.open("a") as fh:
            fh.write(json.dumps(row) + "\n")
        print(f"# [{k}/{len(runs)}] {_progress(row)}", flush=True)
    if args.results:
        settings = {
            "logs": args.logs,
            "seeds": args.seeds,
            "params": str(PARAMS.relative_to(REPO)),
            "build_map_only": args.build_map_only,
            "own_odometry": not args.no_own_odometry,
        }
        written = write_bag_replay_results(
            args.results, rows, argv=sys.argv, clock=clock, settings=settings
        )
        print(f"wrote {written}", flush=True)
    print(
        f"\n--build-map against map build --carmen on the same log and odometry (map build's,"
        f" realistic, seeds {args.seeds}; target: |difference| <= 0.02 m); --build-map on the"
        " log's own odometry (the corrected poses) for comparison:"
    )
    print(
        f"{'log':<14}{'seed':>5}{'--build-map ATE [m]':>20}{'map build ATE [m]':>19}"
        f"{'difference [m]':>16}{'own odometry [m]':>18}"
    )
    nan = float("nan")
    for r in rows:
        m = r["same_input_as_map_build"]
        print(
            f"{r['log']:<14}{r['seed']:>5}{m['build_map_ate'] or nan:>20.3f}"
            f"{m['map_build_ate'] or nan:>19.3f}"
            f"{m['difference'] if m['difference'] is not None else nan:>+16.4f}"
            f"{r['build_map_ate'] or nan:>18.3f}"
        )
    if args.build_map_only:
        return 0
    print(
        "\nOn the experiment's map and odometry (the issue's comparison; targets: |difference|"
        " <= 0.02 m, dropped < 1 %):"
    )
    print(
        f"{'log':<14}{'replay mean [m]':>16}{'amcl-carmen mean [m]':>22}{'difference [m]':>16}"
        f"{'dropped':>9}"
    )
    for r in rows:
        e = r["same_as_experiment"]
        print(
            f"{r['log']:<14}{e['replay_mean']:>16.3f}{e['amcl_carmen_mean']:>22.3f}"
            f"{e['difference']:>+16.3f}{100 * (e['dropped_share'] or 0):>8.2f}%"
        )
    print(
        "\nAs a user runs it (the log's own odometry, replay on the map of map build --carmen;"
        " the SLAM map's own error is in the replay's error):"
    )
    print(
        f"{'log':<14}{'dropped':>9}{'replay mean (map frame / fitted) [m]':>40}"
        f"{'tracked mean [m]':>18}{'--build-map ATE (own odometry)':>32}"
    )
    for r in rows:
        a, t = r["replay_all"], r["replay_tracked"]
        print(
            f"{r['log']:<14}{100 * (r['dropped_share'] or 0):>8.2f}%"
            f"{a['mean']:>28.3f} / {a['mean_aligned']:<9.3f}{t['mean']:>18.3f}"
            f"{r['build_map_ate'] or float('nan'):>32.3f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
