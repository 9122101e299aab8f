"""Benchmark: one full AMCL update vs the C++ ROS 1 amcl core.

Setup as the C++ measurement in issue 5: a 10 m room with obstacles in a 400 x 400 map at
0.05 m, likelihood-field model, 60 beams, differential motion model. One "full update" is
motion + likelihood-field sensor update + resample; symloc's figure also includes the
clustering into hypotheses and building the result (the C++ core clusters inside its resample
too). Particle count fixed (min_particles = max_particles = N). Median of many runs, ms.

Run: ``python benchmarks/bench_amcl.py [--repeats R] [--sizes 2000 5000 ...]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from symloc.grid import OccupancyGrid
from symloc.mcl import Amcl, AmclParams
from symloc.mcl.beam_model import raycast_grid
from symloc.mcl.beams import select_beams
from symloc.mcl.clustering import cluster_particles
from symloc.mcl.likelihood_field import likelihood_field_weights
from symloc.mcl.motion_model import sample_motion_model_odometry
from symloc.mcl.resampling import low_variance_resample
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan

#: C++ ROS 1 amcl core, -O2, same setup: (motion, laser, resample, total) ms per update.
CPP_MS = {
    2000: (0.44, 4.8, 1.3, 6.6),
    5000: (1.1, 12.3, 7.6, 21.0),
    20000: (4.5, 54.0, 118.0, 177.0),
    100000: (22.5, 277.0, 2864.0, 3164.0),
}


def build_map() -> OccupancyGrid:
    """400 x 400 cells at 0.05 m; a 10 m room in the middle with a few obstacles."""
    res = 0.05
    data = np.full((400, 400), -1, dtype=np.int8)
    lo, hi = 100, 300  # 10 m room
    data[lo:hi, lo:hi] = 0
    data[lo, lo:hi] = data[hi - 1, lo:hi] = 100
    data[lo:hi, lo] = data[lo:hi, hi - 1] = 100
    data[140:160, 140:170] = 100
    data[220:230, 180:260] = 100
    data[170:260, 240:246] = 100
    yy, xx = np.mgrid[0:400, 0:400]
    data[(yy - 250) ** 2 + (xx - 140) ** 2 < 12**2] = 100
    return OccupancyGrid(data, res)


def make_scan(grid: OccupancyGrid, pose: np.ndarray, rng: np.random.Generator) -> LaserScan:
    n = 360
    ang = -np.pi + 2 * np.pi / n * np.arange(n)
    r = raycast_grid(grid, np.repeat(pose[None, :2], n, 0), ang + pose[2], 12.0)
    r = r + rng.normal(0.0, 0.01, n)
    return LaserScan(-np.pi, 2 * np.pi / n, 0.1, 12.0, r)


def bench(n: int, repeats: int, grid: OccupancyGrid, seed: int = 0) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    params = AmclParams(max_particles=n, min_particles=n, update_min_d=0.0, update_min_a=0.0)
    amcl = Amcl(grid, params, rng)
    true = np.array([10.0, 10.0, 0.3])
    amcl.initialize_pose(true, np.diag([1.0, 1.0, 0.3]))
    scan = make_scan(grid, true, rng)
    beams = select_beams(scan, 60)
    assert beams.n_hits == 60, beams.n_hits
    odom = np.zeros(3)
    amcl.update(OdometryReading(odom), scan)
    parts = amcl.particles.copy()
    w = amcl.weights
    full, mot, las, res, clu = [], [], [], [], []
    for _ in range(repeats):
        odom = odom + np.array([0.01, 0.0, 0.002])
        t0 = time.perf_counter()
        amcl.update(OdometryReading(odom), scan)
        full.append(time.perf_counter() - t0)
        # the phases one by one on a copy of the set
        t0 = time.perf_counter()
        moved = sample_motion_model_odometry(
            parts, np.zeros(3), np.array([0.05, 0.0, 0.01]), (0.2,) * 5, rng
        )
        t1 = time.perf_counter()
        f = likelihood_field_weights(amcl.field, moved, beams, z_hit=0.5, z_rand=0.5, sigma_hit=0.2)
        t2 = time.perf_counter()
        ww = w * f
        idx = low_variance_resample(ww, n, rng)
        new = moved[idx]
        t3 = time.perf_counter()
        cluster_particles(new, np.full(n, 1.0 / n))
        t4 = time.perf_counter()
        mot.append(t1 - t0)
        las.append(t2 - t1)
        res.append(t3 - t2)
        clu.append(t4 - t3)
    ms = lambda v: 1000.0 * float(np.median(v))  # noqa: E731
    return {
        "n": n,
        "motion": ms(mot),
        "laser": ms(las),
        "resample": ms(res),
        "cluster": ms(clu),
        "full": ms(full),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=0, help="runs per size (0: auto)")
    ap.add_argument("--sizes", type=int, nargs="+", default=[2000, 5000, 20000, 100000])
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    grid = build_map()
    print(f"# bench_amcl seed={args.seed}; 400x400 map at 0.05 m, likelihood field, 60 beams, DIFF")
    print(
        f"{'N':>7} | {'motion':>7} {'laser':>7} {'resamp':>7} {'clust':>7} | {'full':>8} |"
        f" {'C++ m+l+r':>20} {'C++ tot':>8} | {'ratio':>6} | {'us/particle':>11}"
    )
    rows = []
    for n in args.sizes:
        reps = args.repeats or max(15, min(200, 400000 // n))
        r = bench(n, reps, grid, args.seed)
        rows.append(r)
        cpp = CPP_MS.get(n)
        cpp_s = f"{cpp[0]}+{cpp[1]}+{cpp[2]}" if cpp else "-"
        cpp_t = f"{cpp[3]:.1f}" if cpp else "-"
        ratio = f"{r['full'] / cpp[3]:.2f}" if cpp else "-"
        print(
            f"{n:>7} | {r['motion']:7.2f} {r['laser']:7.2f} {r['resample']:7.2f}"
            f" {r['cluster']:7.2f} | {r['full']:8.2f} | {cpp_s:>20} {cpp_t:>8} | {ratio:>6} |"
            f" {1000.0 * r['full'] / n:11.3f}"
        )
    if len(rows) > 1:
        ns = np.array([r["n"] for r in rows], dtype=float)
        ts = np.array([r["full"] for r in rows])
        slope = np.polyfit(np.log(ns), np.log(ts), 1)[0]
        print(
            f"# growth exponent of full update time in N (log-log slope): {slope:.2f} (1 = linear)"
        )
    print("# ratio = symloc full update / C++ total (< 1 is faster than C++)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
