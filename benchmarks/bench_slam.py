"""Benchmark the SLAM pipeline: front-end scans per second and one graph optimisation.

Data: the first ``--scans`` scans of the intel CARMEN log (``../shared/data/carmen`` or
``$SYMLOC_SHARED_DATA``) with odometry noise (GMapping's defaults, seeded) added to the
corrected increments; without the data, a simulated exploration of the L-shaped room.

Prints, as wall-clock and process-CPU times (on a shared machine the wall time includes
waiting for a core):

- front end: scans per second of scan-to-submap matching + submap insertion (no loop search);
- one real-time correlative match (median);
- one loop-closure match (median);
- one Levenberg-Marquardt optimisation of the full pose graph of the run.

Run: ``python benchmarks/bench_slam.py [--scans N] [--seed S]``
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from symloc.geometry import compose, relative
from symloc.sim.odometry_noise import noisy_odometry
from symloc.slam.correlative_scan_matching import match_scan
from symloc.slam.slam import SlamParams, run_slam, scan_points
from symloc.slam.submaps import ActiveSubmaps


def _data(n: int, seed: int) -> tuple[list, np.ndarray, str]:
    env = os.environ.get("SYMLOC_SHARED_DATA")
    base = Path(env) if env else Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
    log = base / "carmen" / "intel-corrected.log.gz"
    if log.is_file():
        from symloc.io.carmen import read_carmen

        lg = read_carmen(log)
        scans = lg.scans[:n]
        ref = np.array([s.laser_pose for s in scans])
        return [s.scan for s in scans], noisy_odometry(ref, rng=seed), f"intel (first {len(scans)})"
    from symloc.bench.exploration import simulate_exploration
    from symloc.sim.rooms import build_room

    run = simulate_exploration(build_room("l_shaped", 4.0, lab=False), rng=seed)
    return run.scans[:n], run.odometry[:n], f"simulated l_shaped (first {min(n, len(run.scans))})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scans", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    scans, odom, label = _data(args.scans, args.seed)
    prm = SlamParams()
    print(f"# bench_slam: {label}, seed {args.seed}")

    # front end only: predict, match against the oldest active submap, insert
    active = ActiveSubmaps(prm.submap)
    local = np.zeros((len(scans), 3))
    match_wall: list[float] = []
    match_cpu: list[float] = []
    w0, c0 = time.perf_counter(), time.process_time()
    for i, scan in enumerate(scans):
        pts = scan_points(scan, prm.max_range, prm.voxel)
        if i == 0:
            local[0] = odom[0]
        else:
            pred = compose(local[i - 1], relative(odom[i - 1], odom[i]))
            target = active.matching_submap
            assert target is not None
            table = target.table()
            mw, mc = time.perf_counter(), time.process_time()
            res = match_scan(table, pts, relative(target.local_pose, pred), prm.local_csm)
            match_wall.append(time.perf_counter() - mw)
            match_cpu.append(time.process_time() - mc)
            local[i] = compose(target.local_pose, res.pose)
        active.insert(i, local[i], scan)
    fw, fc = time.perf_counter() - w0, time.process_time() - c0
    n = len(scans)
    print(f"front end: {n / fw:.1f} scans/s wall, {n / fc:.1f} scans/s CPU ({n} scans)")
    print(
        f"real-time match: median {1e3 * np.median(match_wall):.2f} ms wall,"
        f" {1e3 * np.median(match_cpu):.2f} ms CPU"
    )

    # loop-closure match: a late scan against the first finished submap
    sm = next(s for s in active.submaps if s.finished)
    table = sm.table()
    pts = scan_points(scans[sm.nodes[5]], prm.max_range, prm.voxel)
    guess = sm.node_poses[5] + np.array([0.8, -0.6, 0.1])
    lw, lc = [], []
    for _ in range(5):
        a, b = time.perf_counter(), time.process_time()
        match_scan(table, pts, guess, prm.loop_csm)
        lw.append(time.perf_counter() - a)
        lc.append(time.process_time() - b)
    print(
        f"loop-closure match: median {1e3 * np.median(lw):.1f} ms wall, {1e3 * np.median(lc):.1f} ms CPU"
    )

    # one optimisation of the full graph of a complete run (from the initial guesses)
    res = run_slam(scans, odom, prm, progress=False)
    graph = res.graph
    assert graph is not None
    import gtsam

    initial = gtsam.Values()
    for i in range(graph.n_nodes):
        p = res.local_poses[i]
        initial.insert(gtsam.symbol("x", i), gtsam.Pose2(p[0], p[1], p[2]))
    for j in range(graph.n_submaps):
        p = graph.submap_pose(j)
        initial.insert(gtsam.symbol("s", j), gtsam.Pose2(p[0], p[1], p[2]))
    ow, oc = [], []
    for _ in range(3):
        graph.values = initial
        a, b = time.perf_counter(), time.process_time()
        graph.optimize()
        ow.append(time.perf_counter() - a)
        oc.append(time.process_time() - b)
    print(
        f"one graph optimisation ({graph.n_nodes} nodes, {graph.n_submaps} submaps,"
        f" {graph.graph.size()} factors, {len(res.loop_closures)} loop closures, from the"
        f" front-end poses): median {1e3 * np.median(ow):.1f} ms wall,"
        f" {1e3 * np.median(oc):.1f} ms CPU"
    )


if __name__ == "__main__":
    main()
