"""Benchmark: symloc's AMCL against a peer AMCL core, measured in the same run.

Two benchmarks, each driving symloc and (optionally) a peer on *identical input*:

``update`` (default)
    One full filter update (motion + likelihood-field sensor update + resample + clustering)
    on a 10 m room in a 400 x 400 map at 0.05 m, 60 beams, the differential motion model,
    every scan integrated, KLD-sampling on (``min_particles = N - 1``, so both sides do their
    adaptive-sampling work and keep about N particles), resampling every update. Per update:
    CPU time [ms] (the process's, so both cores count when symloc uses them; both sides the
    same span: symloc's ``Amcl.update``, the driver's whole handling of a scan -- motion,
    sensor update, resampling, cluster statistics), the laser step in ns per particle-beam
    (the peer's ``laser_cpu``, printed by the driver of ``benchmarks/peers/amcl_core``), and the
    peak resident memory of the whole process [MiB]; ``--results`` writes the rows as a results
    file (the README's: ``docs/results/bench_amcl_update.json``).
``--carmen DIR``
    End to end on real logs: for each CARMEN log in DIR (and ``--large``: a generated map of
    5,200 x 5,200 cells with a simulated drive) the map (log-odds, 5 cm), the scans and noisy
    odometry of ``symloc experiment amcl-carmen``'s tracking are written to one problem file;
    symloc's :class:`~symloc.mcl.Amcl` and the peer each run over it as a separate process
    with the same settings (likelihood_field_prob, 60 beams, 2,000 / 500 particles, nav2's
    update thresholds tested per axis as ROS 1 does, resampling every update), and the same
    between-update pose carrying (the last estimate moved by the odometry). Reported: process
    CPU time [s], peak memory [MiB] and the tracking error against the corrected poses; on
    the large map also global localization with 20,000 particles.

The peer is any program that reads the problem file and prints, per record, ``updated x y
theta n_particles`` and a last line ``# ...`` (the format is below): the C++ ROS 1 amcl core
(ros-planning/navigation, noetic-devel, ``amcl/src/amcl``) with a small driver is what the
README's table used: the driver and its build script are in ``benchmarks/peers/amcl_core``
(``build.sh NAVIGATION/amcl OUT_DIR``; the core itself is fetched, not shipped). ``--peer CMD`` is the
stock core, ``--peer-fair CMD`` the same core with an O(N log N) resampler (binary search in
the cumulative weights instead of its linear scan). Without a peer only symloc's figures are
printed. Runs alternate symloc, peer, fair peer; each figure is the median over ``--rounds``
with the 1-minute load average beside it.

Problem file (little-endian): ``b"SYMLAMC1"``; map ``int32 W, H``, ``float64 resolution,
origin_x, origin_y`` (the corner of cell (0, 0) plus half a cell: cell ``(i, j)``'s centre,
the convention of ROS 1 amcl's ``map_t``); parameters ``float64 z_hit, z_rand, sigma_hit,
max_occ_dist, alpha1..5``, ``int32 min_particles, max_particles``, ``float64 pf_err, pf_z``
(the normal *quantile*, as symloc uses it), ``float64 alpha_slow, alpha_fast, update_min_d,
update_min_a``, ``int32 resample_interval, max_beams, laser_model (0 likelihood_field,
1 likelihood_field_prob), odom_model (0 diff, 1 diff-corrected), init (0 Gaussian, 1 uniform
over free cells)``, ``float64 mean[3], covariance diagonal[3]``, ``int32 records``; then
``W * H`` int8 cells (-1 free, 0 unknown, +1 occupied, row-major from the origin); then per
record ``float64 odom x, y, theta``, ``int32 n``, ``float64 angle_min, angle_increment,
range_min, range_max``, ``float32 ranges[n]``.

Run: ``python benchmarks/bench_amcl.py [--sizes 2000 20000 100000] [--peer CMD --peer-fair
CMD] [--carmen DIR [--large]]``
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import shlex
import struct
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import compose, inverse, wrap_angle
from symloc.grid import OccupancyGrid
from symloc.mcl import Amcl, AmclParams
from symloc.mcl.beam_model import raycast_grid
from symloc.mcl.kld_sampling import pf_z_quantile
from symloc.odometry import OdometryReading
from symloc.runtime import PROCESS_ENV, configure_process
from symloc.scan import LaserScan

FloatArray = NDArray[np.float64]
MAGIC = b"SYMLAMC1"


# ----------------------------------------------------------------------------- problem file
@dataclass
class Problem:
    grid: OccupancyGrid
    params: AmclParams
    init_global: bool
    mean: FloatArray
    cov_diag: FloatArray
    odom: FloatArray  # (T, 3)
    scans: list[LaserScan]


def write_problem(path: Path, pr: Problem) -> None:
    g, p = pr.grid, pr.params
    h, w = g.data.shape
    occ = np.zeros((h, w), np.int8)
    occ[g.free_mask] = -1
    occ[g.occupied_mask] = 1
    o = np.asarray(g.origin, dtype=np.float64)
    assert o[2] == 0.0, "rotated map origins are not supported by the peer's map_t"
    lm = {"likelihood_field": 0, "likelihood_field_prob": 1}[p.laser_model_type]
    om = {"diff": 0, "diff-corrected": 1}[p.motion_model]
    with path.open("wb") as fh:
        fh.write(MAGIC)
        fh.write(
            struct.pack(
                "<ii3d", w, h, g.resolution, o[0] + g.resolution / 2, o[1] + g.resolution / 2
            )
        )
        fh.write(
            struct.pack(
                "<9d2i2d4d5i",
                p.z_hit,
                p.z_rand,
                p.sigma_hit,
                p.laser_likelihood_max_dist,
                p.alpha1,
                p.alpha2,
                p.alpha3,
                p.alpha4,
                p.alpha5,
                p.min_particles,
                p.max_particles,
                p.pf_err,
                pf_z_quantile(p.pf_z),
                p.recovery_alpha_slow,
                p.recovery_alpha_fast,
                p.update_min_d,
                p.update_min_a,
                p.resample_interval,
                p.max_beams,
                lm,
                om,
                1 if pr.init_global else 0,
            )
        )
        fh.write(struct.pack("<6di", *pr.mean, *pr.cov_diag, len(pr.scans)))
        fh.write(occ.tobytes())
        for od, s in zip(pr.odom, pr.scans, strict=True):
            r = np.asarray(s.ranges, dtype=np.float32)
            rmax = p.laser_max_range if p.laser_max_range > 0 else s.range_max
            rmin = max(s.range_min, p.laser_min_range)
            fh.write(struct.pack("<3di4d", *od, r.size, s.angle_min, s.angle_increment, rmin, rmax))
            fh.write(r.tobytes())


def read_problem(path: Path) -> Problem:
    buf = path.read_bytes()
    if buf[:8] != MAGIC:
        raise SystemExit(f"{path}: not a problem file")
    off = 8

    def take(fmt: str) -> tuple[Any, ...]:
        nonlocal off
        v = struct.unpack_from(fmt, buf, off)
        off += struct.calcsize(fmt)
        return v

    w, h, res, ox, oy = take("<ii3d")
    v = take("<9d2i2d4d5i")
    mean_cov = take("<6di")
    occ = np.frombuffer(buf, np.int8, w * h, off).reshape(h, w)
    off += w * h
    data = np.full((h, w), -1, np.int8)
    data[occ == 1] = 100
    data[occ == -1] = 0
    grid = OccupancyGrid(data, res, (ox - res / 2, oy - res / 2, 0.0))
    z_hit, z_rand, sigma, maxd, a1, a2, a3, a4, a5 = v[:9]
    min_p, max_p = v[9:11]
    pf_err, pf_zq, a_slow, a_fast, dmin, amin = v[11:17]
    interval, beams, lm, om, init = v[17:22]
    n = mean_cov[6]
    odom = np.empty((n, 3))
    scans = []
    rmax_all = 0.0
    for k in range(n):
        x, y, t, nb, a0, ai, rmin, rmax = take("<3di4d")
        odom[k] = x, y, t
        r = np.frombuffer(buf, np.float32, nb, off).astype(np.float64)
        off += 4 * nb
        scans.append(LaserScan(a0, ai, rmin, rmax, r))
        rmax_all = rmax
    params = AmclParams(
        z_hit=z_hit,
        z_rand=z_rand,
        sigma_hit=sigma,
        laser_likelihood_max_dist=maxd,
        alpha1=a1,
        alpha2=a2,
        alpha3=a3,
        alpha4=a4,
        alpha5=a5,
        min_particles=min_p,
        max_particles=max_p,
        pf_err=pf_err,
        pf_z=float(0.5 * math.erfc(-pf_zq / math.sqrt(2.0))),
        recovery_alpha_slow=a_slow,
        recovery_alpha_fast=a_fast,
        update_min_d=dmin,
        update_min_a=amin,
        update_min_d_euclidean=False,
        resample_interval=interval,
        max_beams=beams,
        laser_model_type=["likelihood_field", "likelihood_field_prob"][lm],
        robot_model_type=["diff", "diff-corrected"][om],
        laser_max_range=rmax_all,
    )
    return Problem(
        grid, params, bool(init), np.array(mean_cov[:3]), np.array(mean_cov[3:6]), odom, scans
    )


def vm_hwm_mib(field: str = "VmHWM") -> float:
    """This process image's peak (``VmHWM``) or current (``VmRSS``) resident memory [MiB]; not
    the parent's, as ``ru_maxrss`` would carry across exec."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return float(line.split()[1]) / 1024.0
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def worker(path: Path, seed: int, *, judge: bool = True) -> int:
    """symloc over a problem file, printing what a peer prints (see the module docstring).

    With ``judge`` each filter result is also judged by a
    :class:`~symloc.mcl.confidence.ConfidenceJudge` (the confidence verdict with its rival
    search, what the localizer, the node and ``symloc experiment amcl-carmen`` run per scan);
    without it only the filter runs, as the peer does. Reports whether the per-scan kernels
    ran from their ahead-of-time build (:mod:`symloc.mcl.aot`; ``python -m
    symloc.mcl.aot_build``) or from numba's JIT.
    """
    from symloc.mcl import kernels
    from symloc.mcl.confidence import ConfidenceJudge

    base = vm_hwm_mib("VmRSS")  # the interpreter and the libraries, before any work
    t0 = time.process_time()
    pr = read_problem(path)
    t_read = time.process_time() - t0
    t0 = time.process_time()
    amcl = Amcl(pr.grid, pr.params, np.random.default_rng(seed))
    judge_of = ConfidenceJudge(amcl) if judge else None
    t_map = time.process_time() - t0
    t_judge = 0.0
    n_confident = 0
    if pr.init_global:
        amcl.initialize_global()
    else:
        amcl.initialize_pose(pr.mean, np.diag(pr.cov_diag))
    n_upd = 0
    t_upd = 0.0
    lines = []
    for od, scan in zip(pr.odom, pr.scans, strict=True):
        t1 = time.process_time()
        reading = OdometryReading(od)
        res = amcl.update(reading, scan)
        t_upd += time.process_time() - t1
        if judge_of is not None:
            t1 = time.process_time()
            n_confident += int(judge_of(res, reading, scan).confident)
            t_judge += time.process_time() - t1
        n_upd += int(res.updated)
        e = res.estimate
        lines.append(
            f"{int(res.updated)} {e[0]:.9f} {e[1]:.9f} {e[2]:.9f} {res.particles.shape[0]}"
        )
    total = time.process_time() - t0
    sys.stdout.write("\n".join(lines) + "\n")
    print(
        f"# updates {n_upd} map_cpu {t_map:.6f} update_cpu {t_upd:.6f} total_cpu {total:.6f}"
        f" read_cpu {t_read:.6f} vmhwm_mib {vm_hwm_mib():.1f} base_mib {base:.1f}"
        f" judge_cpu {t_judge:.6f} rival_searches"
        f" {0 if judge_of is None else judge_of.n_rival_searches} confident {n_confident}"
        f" aot_kernels {int(kernels.endpoint_table_sum.ahead_of_time)}"
    )
    return 0


# ----------------------------------------------------------------------------- running
@dataclass
class RunResult:
    updated: NDArray[np.bool_]
    estimate: FloatArray
    n_particles: NDArray[np.int64]
    summary: dict[str, float]
    cpu_s: float  # the whole process: user + system
    peak_mib: float


def run_side(cmd: list[str]) -> RunResult:
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out, err = proc.communicate()
    if proc.returncode != 0:
        raise SystemExit(f"{cmd[0]} failed ({proc.returncode}): {err[-2000:]}")
    rows = [ln.split() for ln in out.splitlines() if ln and not ln.startswith("#")]
    tail = [ln for ln in out.splitlines() if ln.startswith("#")][-1].split()[1:]
    summary = {tail[i]: float(tail[i + 1]) for i in range(0, len(tail) - 1, 2)}
    arr = np.array([[float(v) for v in r] for r in rows]) if rows else np.zeros((0, 5))
    peak = summary.get("vmhwm_mib", math.nan)
    return RunResult(
        arr[:, 0] > 0.5, arr[:, 1:4], arr[:, 4].astype(np.int64), summary, math.nan, peak
    )


def run_timed(cmd: list[str]) -> RunResult:
    """Run ``cmd``; its CPU time from the kernel's accounting of the finished child."""
    before = os.times()
    r = run_side(cmd)
    after = os.times()
    r.cpu_s = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    return r


def symloc_cmd(problem: Path, seed: int, *, judge: bool = True) -> list[str]:
    return [
        sys.executable,
        str(Path(__file__).resolve()),
        "--worker",
        str(problem),
        "--seed",
        str(seed),
        *([] if judge else ["--no-judge"]),
    ]


def peer_cmd(cmd: str, problem: Path, seed: int) -> list[str]:
    return [*shlex.split(cmd), str(problem), str(seed)]


def load() -> str:
    return f"{os.getloadavg()[0]:.2f}"


# ----------------------------------------------------------------------------- update bench
def room_map() -> OccupancyGrid:
    """400 x 400 cells at 0.05 m; a 10 m room in the middle with a few obstacles."""
    data = np.full((400, 400), -1, dtype=np.int8)
    lo, hi = 100, 300
    data[lo:hi, lo:hi] = 0
    data[lo, lo:hi] = data[hi - 1, lo:hi] = 100
    data[lo:hi, lo] = data[lo:hi, hi - 1] = 100
    data[140:160, 140:170] = 100
    data[220:230, 180:260] = 100
    data[170:260, 240:246] = 100
    yy, xx = np.mgrid[0:400, 0:400]
    data[(yy - 250) ** 2 + (xx - 140) ** 2 < 12**2] = 100
    return OccupancyGrid(data, 0.05)


build_map = room_map  # the name older scripts import


def make_scan(
    grid: OccupancyGrid, pose: FloatArray, rng: np.random.Generator, n: int = 360
) -> LaserScan:
    ang = -np.pi + 2 * np.pi / n * np.arange(n)
    r = raycast_grid(grid, np.repeat(pose[None, :2], n, 0), ang + pose[2], 12.0)
    r = r + rng.normal(0.0, 0.01, n)
    return LaserScan(-np.pi, 2 * np.pi / n, 0.1, 12.0, r)


def update_problem(n: int, updates: int, seed: int) -> Problem:
    grid = room_map()
    rng = np.random.default_rng(seed)
    true = np.array([10.0, 10.0, 0.3])
    scan = make_scan(grid, true, rng)
    params = AmclParams(
        max_particles=n,
        min_particles=n - 1,
        update_min_d=0.0,
        update_min_a=0.0,
        update_min_d_euclidean=False,
        laser_model_type="likelihood_field",
        z_hit=0.5,
        z_rand=0.5,
    )
    odom = np.zeros((updates + 1, 3))
    odom[:, 0] = 0.01 * np.arange(updates + 1)
    odom[:, 2] = 0.002 * np.arange(updates + 1)
    return Problem(
        grid, params, False, true, np.array([1.0, 1.0, 0.3]), odom, [scan] * (updates + 1)
    )


def update_bench(args: argparse.Namespace, tmp: Path) -> list[dict[str, Any]]:
    """Run the update benchmark; print its table and return its rows (one per particle count
    and side: CPU ms per update, laser ns per particle-beam, peak and work MiB, mean particle
    count, the ratios to the stock and the fair core, the median load average)."""
    rows: list[dict[str, Any]] = []
    sides = [("symloc", None)]
    if args.peer:
        sides.append(("C++", args.peer))
    if args.peer_fair:
        sides.append(("C++ fair", args.peer_fair))
    print(
        f"# bench_amcl update: seed={args.seed}, rounds={args.rounds}; 400x400 map at 0.05 m,"
        " likelihood_field, 60 beams, diff-corrected, KLD on (min = N - 1), resample every"
        " update; CPU ms per update (whole process, all threads), median over rounds; peak ="
        " the process's peak resident memory, work = peak minus its resident memory before"
        " any work (symloc: the interpreter and libraries loaded)"
    )
    print(
        f"{'N':>7} {'side':>9} | {'ms/update':>9} {'laser ns/pb':>11} {'peak MiB':>8}"
        f" {'work MiB':>8} {'particles':>9} | {'/ C++':>6} {'/ fair':>6} | load"
    )
    for n in args.sizes:
        ups = args.updates or max(20, min(200, 2_000_000 // n))
        prob = tmp / f"update_{n}.bin"
        write_problem(prob, update_problem(n, ups, args.seed))
        per: dict[str, list[tuple[float, float, float, float]]] = {s: [] for s, _ in sides}
        loads = []
        for rnd in range(args.rounds):
            for name, cmd in sides:
                c = (
                    symloc_cmd(prob, args.seed + rnd, judge=False)
                    if cmd is None
                    else peer_cmd(cmd, prob, args.seed + rnd)
                )
                r = run_timed(c)
                loads.append(os.getloadavg()[0])
                nu = max(1, int(r.summary["updates"]) - 1)
                if cmd is None:
                    ms = 1000.0 * r.summary["update_cpu"] / (nu + 1)
                    las = math.nan
                else:  # the same span as symloc's Amcl.update: the driver's update_cpu
                    ms = 1000.0 * r.summary["update_cpu"] / (nu + 1)
                    las = 1e9 * r.summary.get("laser_cpu", math.nan) / ((nu + 1) * n * 60)
                work = r.peak_mib - r.summary.get("base_mib", 0.0)
                per[name].append((ms, las, r.peak_mib, work, float(np.mean(r.n_particles))))
        med = {s: np.median(np.array(v), axis=0) for s, v in per.items()}
        las_sym = laser_ns(n, args.seed)
        for name, _ in sides:
            ms, las, peak, work, parts = med[name]
            if name == "symloc":
                las = las_sym
            rc = f"{ms / med['C++'][0]:6.2f}" if "C++" in med else "     -"
            rf = f"{ms / med['C++ fair'][0]:6.2f}" if "C++ fair" in med else "     -"
            print(
                f"{n:>7} {name:>9} | {ms:9.2f} {las:11.2f} {peak:8.1f} {work:8.1f} {parts:9.0f}"
                f" | {rc} {rf}"
                f" | {np.median(loads):.2f}"
            )
            rows.append(
                {
                    "particles": n,
                    "side": name,
                    "updates": ups,
                    "cpu_ms_per_update": round(float(ms), 4),
                    "laser_ns_per_particle_beam": round(float(las), 3),
                    "peak_mib": round(float(peak), 1),
                    "work_mib": round(float(work), 1),
                    "mean_particles": round(float(parts), 1),
                    "cpu_ratio_stock": (
                        round(float(ms / med["C++"][0]), 4) if "C++" in med else None
                    ),
                    "cpu_ratio_fair": (
                        round(float(ms / med["C++ fair"][0]), 4) if "C++ fair" in med else None
                    ),
                    "load": round(float(np.median(loads)), 2),
                }
            )
    return rows


def laser_ns(n: int, seed: int) -> float:
    """symloc's laser step alone, one thread: ns per particle-beam (thread CPU time)."""
    from symloc.grid.fields import distance_field
    from symloc.mcl import kernels
    from symloc.mcl.likelihood_field import endpoint_table_sums, laser_poses_grid

    grid = room_map()
    field = distance_field(grid, 2.0)
    rng = np.random.default_rng(seed)
    parts = np.column_stack([rng.normal(10, 1, n), rng.normal(10, 1, n), rng.uniform(-3, 3, n)])
    r = rng.uniform(0.5, 5, 60)
    a = np.linspace(-np.pi, np.pi, 60, endpoint=False)
    tab = field.table("pz3", 0.5, 0.5, 0.2, 12.0)
    poses = laser_poses_grid(field, parts, np.zeros(3))
    saved = kernels.n_threads
    kernels.n_threads = lambda: 1  # type: ignore[assignment]
    try:
        endpoint_table_sums(field, poses, r, a, tab)
        ts = []
        for _ in range(max(5, 2_000_000 // n)):
            t0 = time.thread_time()
            endpoint_table_sums(field, poses, r, a, tab)
            ts.append(time.thread_time() - t0)
    finally:
        kernels.n_threads = saved  # type: ignore[assignment]
    return 1e9 * float(np.median(ts)) / (n * 60)


# ----------------------------------------------------------------------------- end to end
def carmen_problems(
    folder: Path, cache: Path, seed: int, logs: list[str]
) -> list[tuple[str, Problem, FloatArray]]:
    from symloc.experiments.amcl_carmen import build_map as carmen_map
    from symloc.experiments.amcl_carmen import noisy_odometry
    from symloc.io.carmen import read_carmen

    out = []
    for k, name in enumerate(logs):
        path = folder / f"{name}-corrected.log.gz"
        if not path.is_file():
            print(f"# {name}: {path} not found, skipped")
            continue
        log = read_carmen(path)
        grid = carmen_map(log, cache=cache / f"map_{name}.npz")
        truth = log.laser_poses.copy()
        truth[:, 2] = wrap_angle(truth[:, 2])
        odom = noisy_odometry(truth, (0.01,) * 4, np.random.default_rng([seed, k, 0]))
        out.append((name, tracking_problem(grid, truth, odom, [s.scan for s in log.scans]), truth))
    return out


def tracking_problem(
    grid: OccupancyGrid, truth: FloatArray, odom: FloatArray, scans: list[LaserScan]
) -> Problem:
    a = 0.01
    params = AmclParams(
        laser_model_type="likelihood_field_prob",
        alpha1=a,
        alpha2=a,
        alpha3=a,
        alpha4=a,
        laser_max_range=49.9,
        max_particles=2000,
        min_particles=500,
        update_min_d_euclidean=False,
    )
    cov = np.array([0.25, 0.25, (np.pi / 12.0) ** 2])
    return Problem(grid, params, False, truth[0].copy(), cov, odom, scans)


def large_world(seed: int) -> tuple[OccupancyGrid, FloatArray, FloatArray, list[LaserScan]]:
    """5,200 x 5,200 cells at 0.05 m (260 m square): offices 4 m wide between corridors 2 m
    wide every 20 m, walls three cells thick; a drive around one block of corridors with a
    simulated 360-beam lidar (30 m, 1 cm noise) and noisy odometry."""
    from symloc.experiments.amcl_carmen import noisy_odometry

    rng = np.random.default_rng(seed)
    n = 5200
    d = np.full((n, n), -1, np.int8)
    d[100:-100, 100:-100] = 0
    for r in range(100, n - 100, 80):  # office walls every 4 m
        d[r : r + 3, 100:-100] = 100
    for c in range(100, n - 100, 80):
        d[100:-100, c : c + 3] = 100
    for k in range(100, n - 100, 400):  # corridors every 20 m, 2 m wide
        d[k + 20 : k + 60, 100:-100] = 0
        d[100:-100, k + 20 : k + 60] = 0
    d[100:103, 100:-100] = d[-103:-100, 100:-100] = 100
    d[100:-100, 100:103] = d[100:-100, -103:-100] = 100
    holes = rng.random((n // 80, n // 80)) < 0.3  # doors
    for i, j in zip(*np.nonzero(holes), strict=True):
        r, c = 100 + 80 * i, 100 + 80 * j + 30
        if r + 3 < n - 100 and c + 20 < n - 100:
            d[r : r + 3, c : c + 20] = 0
    grid = OccupancyGrid(d, 0.05)
    # a loop along the corridors of one block: centre lines at cells k + 40
    a0, a1 = (900 + 40) * 0.05, (1700 + 40) * 0.05
    corners = np.array([[a0, a0], [a1, a0], [a1, a1], [a0, a1], [a0, a0]])
    pts = []
    for p, q in itertools.pairwise(corners):
        steps = int(np.hypot(*(q - p)) / 0.1)
        heading = math.atan2(q[1] - p[1], q[0] - p[0])
        for s in range(steps):
            pts.append([*(p + (q - p) * s / steps), heading])
    truth = np.array(pts)
    odom = noisy_odometry(truth, (0.01,) * 4, rng)
    nb = 360
    ang = -np.pi + 2 * np.pi / nb * np.arange(nb)
    scans = []
    for pose in truth:
        r = raycast_grid(grid, np.repeat(pose[None, :2], nb, 0), ang + pose[2], 30.0)
        r = np.where(r < 30.0, r + rng.normal(0.0, 0.01, nb), 30.0)
        scans.append(LaserScan(-np.pi, 2 * np.pi / nb, 0.1, 30.0, r))
    return grid, truth, odom, scans


def carried(r: RunResult, odom: FloatArray) -> FloatArray:
    """Per record: the last update's estimate moved by the odometry since that update."""
    out = np.empty_like(odom)
    last_e, last_o = r.estimate[0], odom[0]
    for k in range(odom.shape[0]):
        if r.updated[k] or k == 0:
            last_e, last_o = r.estimate[k], odom[k]
        out[k] = compose(last_e, compose(inverse(last_o), odom[k]))
    return out


def kernels_label(ahead: list[float]) -> str:
    """How symloc's per-scan kernels ran over the rounds (the workers' ``aot_kernels`` flags)."""
    if min(ahead) > 0.5:
        return "ahead of time"
    return "numba JIT" if max(ahead) < 0.5 else "mixed"


def carmen_bench(args: argparse.Namespace, tmp: Path) -> list[dict[str, Any]]:
    """Run the end-to-end benchmark; print its table and return its rows (one per log and
    side: medians over the rounds, ``global`` rows for the large map's global localization)."""
    rows: list[dict[str, Any]] = []
    cache = Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    problems = (
        carmen_problems(Path(args.carmen), cache, args.seed, args.logs) if args.carmen else []
    )
    if args.large:
        grid, truth, odom, scans = large_world(args.seed)
        problems.append(("large", tracking_problem(grid, truth, odom, scans), truth))
    sides = [("symloc", None)] + ([("C++", args.peer)] if args.peer else [])
    print(
        f"# bench_amcl end to end: seed={args.seed}, rounds={args.rounds}; tracking with"
        " likelihood_field_prob, 60 beams, 2000/500 particles, update thresholds per axis"
        " (0.25 m, 0.2 rad), resample every update, odometry noise 0.01; CPU s and peak MiB"
        " of the whole process (map preprocessing included), error = mean position error of"
        " the carried pose against the corrected poses"
    )
    print(
        f"{'log':>10} {'cells':>11} {'side':>7} | {'cpu s':>7} {'peak MiB':>8} {'err m':>7}"
        f" {'p95 m':>6} {'updates':>7} | {'cpu/C++':>7} {'err/C++':>7} | load"
    )
    for name, pr, truth in problems:
        prob = tmp / f"track_{name}.bin"
        write_problem(prob, pr)
        res: dict[str, list[tuple[float, float, float, float, float]]] = {s: [] for s, _ in sides}
        loads = []
        judged: tuple[list[float], list[float]] = ([], [])
        ahead: list[float] = []
        for rnd in range(args.rounds):
            for side, cmd in sides:
                c = (
                    symloc_cmd(prob, args.seed + rnd, judge=args.judge)
                    if cmd is None
                    else peer_cmd(cmd, prob, args.seed + rnd)
                )
                r = run_timed(c)
                loads.append(os.getloadavg()[0])
                if cmd is None:
                    judged[0].append(r.summary.get("judge_cpu", 0.0))
                    judged[1].append(r.summary.get("rival_searches", 0.0))
                    ahead.append(r.summary.get("aot_kernels", 0.0))
                est = carried(r, pr.odom)
                err = np.hypot(est[:, 0] - truth[:, 0], est[:, 1] - truth[:, 1])
                res[side].append(
                    (
                        r.cpu_s,
                        r.peak_mib,
                        float(err.mean()),
                        float(np.percentile(err, 95)),
                        float(r.updated.sum()),
                    )
                )
        med = {s: np.median(np.array(v), axis=0) for s, v in res.items()}
        cells = f"{pr.grid.data.shape[1]}x{pr.grid.data.shape[0]}"
        for side, _ in sides:
            cpu, peak, err, p95, nu = med[side]
            rc = f"{cpu / med['C++'][0]:7.2f}" if "C++" in med else "      -"
            re_ = f"{err / med['C++'][2]:7.2f}" if "C++" in med else "      -"
            rows.append(
                {
                    "log": name,
                    "cells": cells,
                    "side": side,
                    "cpu_s": float(cpu),
                    "peak_mib": float(peak),
                    "error_mean_m": float(err),
                    "error_p95_m": float(p95),
                    "updates": int(nu),
                    "cpu_ratio": float(cpu / med["C++"][0]) if "C++" in med else None,
                    "error_ratio": float(err / med["C++"][2]) if "C++" in med else None,
                    "load": float(np.median(loads)),
                    "judge_cpu_s": float(np.median(judged[0])) if side == "symloc" else None,
                    "rival_searches": float(np.median(judged[1])) if side == "symloc" else None,
                    "kernels": kernels_label(ahead) if side == "symloc" else None,
                }
            )
            print(
                f"{name:>10} {cells:>11} {side:>7} | {cpu:7.2f} {peak:8.1f} {err:7.3f} {p95:6.3f}"
                f" {nu:7.0f} | {rc} {re_} | {np.median(loads):.2f}"
                + (
                    f" | judge {np.median(judged[0]):.2f} s, {np.median(judged[1]):.0f} rival"
                    " searches"
                    if side == "symloc" and args.judge
                    else ""
                )
                + (f" | kernels {rows[-1]['kernels']}" if side == "symloc" else "")
            )
        if name == "large" and args.global_particles:
            g = Problem(
                pr.grid,
                pr.params.replace(max_particles=args.global_particles, min_particles=500),
                True,
                pr.mean,
                pr.cov_diag,
                pr.odom[:30],
                pr.scans[:30],
            )
            gp = tmp / "global_large.bin"
            write_problem(gp, g)
            for side, cmd in sides:
                c = (
                    symloc_cmd(gp, args.seed, judge=args.judge)
                    if cmd is None
                    else peer_cmd(cmd, gp, args.seed)
                )
                r = run_timed(c)
                rows.append(
                    {
                        "log": "large (global)",
                        "side": side,
                        "particles": args.global_particles,
                        "cpu_s": r.cpu_s,
                        "peak_mib": r.peak_mib,
                    }
                )
                print(
                    f"# global localization on the large map, {args.global_particles} particles,"
                    f" 30 scans: {side} cpu {r.cpu_s:.2f} s, peak {r.peak_mib:.1f} MiB"
                    f" (load {load()})"
                )
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[2000, 20000, 100000])
    ap.add_argument("--updates", type=int, default=0, help="updates per run (0: auto)")
    ap.add_argument("--rounds", type=int, default=3, help="alternating rounds (median)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--peer", help="command of the peer AMCL driver (stock)")
    ap.add_argument("--peer-fair", help="command of the peer driver with the fair resampler")
    ap.add_argument("--carmen", help="folder of CARMEN logs: the end-to-end benchmark")
    ap.add_argument("--logs", nargs="+", default=None, help="log names (default: every log)")
    ap.add_argument("--large", action="store_true", help="also the generated 5,200^2 map")
    ap.add_argument("--global-particles", type=int, default=20000)
    ap.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "symloc-bench-amcl"))
    ap.add_argument(
        "--no-judge",
        dest="judge",
        action="store_false",
        help="end to end: symloc's filter alone, without the confidence verdict and its rival"
        " search (by default each update is also judged, as the localizer and the node do)",
    )
    ap.add_argument(
        "--results",
        default=None,
        metavar="PATH",
        help="also write a results file with the rows, command, commit, date, machine and "
        "load (the README's: docs/results/bench_amcl_carmen.json end to end, --carmen/--large; "
        "docs/results/bench_amcl_update.json for the update benchmark); python -m symloc.readme "
        "re-renders the README from it",
    )
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        return worker(Path(args.worker), args.seed, judge=args.judge)
    # symloc's workers start as the symloc command does (one BLAS thread, symloc.runtime);
    # the peer's process does not link a BLAS
    configure_process()
    print(f"# symloc workers' environment: {dict(PROCESS_ENV)} (symloc.runtime)")
    if args.logs is None:  # every log in the folder
        folder = Path(args.carmen) if args.carmen else Path(".")
        args.logs = sorted(p.name.split("-corrected")[0] for p in folder.glob("*-corrected.log.gz"))
    print(f"# load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}; {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory(prefix="symloc-bench-amcl-") as d:
        if args.carmen or args.large:
            # the parent's alone: the worker process imports only what a symloc user's does
            from symloc.bench.provenance import RunClock, peer_source
            from symloc.bench.results_file import write_run_results

            clock = RunClock()
            rows = carmen_bench(args, Path(d))
            if args.results:
                settings = {
                    k: getattr(args, k)
                    for k in ("seed", "rounds", "logs", "large", "global_particles", "judge")
                }
                settings["symloc_env"] = dict(PROCESS_ENV)
                settings["peer"] = (
                    peer_source(args.peer, "the noetic amcl core (benchmarks/peers/amcl_core)")
                    if args.peer
                    else None
                )
                written = write_run_results(
                    args.results,
                    argv=sys.argv,
                    clock=clock,
                    settings=settings,
                    figures={"rows": rows},
                    program="python",
                    workers=1,
                )
                print(f"wrote {written}")
        else:
            from symloc.bench.provenance import RunClock, peer_source
            from symloc.bench.results_file import write_bench_results

            clock = RunClock()
            rows = update_bench(args, Path(d))
            if args.results:
                settings = {k: getattr(args, k) for k in ("seed", "rounds", "sizes", "updates")}
                settings["peer"] = (
                    peer_source(args.peer, "the noetic amcl core (benchmarks/peers/amcl_core)")
                    if args.peer
                    else None
                )
                settings["peer_fair"] = (
                    peer_source(
                        args.peer_fair,
                        "the same core with fair_resampler.patch (build.sh with FAIR=1)",
                    )
                    if args.peer_fair
                    else None
                )
                written = write_bench_results(
                    args.results, clock=clock, settings=settings, figures={"rows": rows}
                )
                print(f"wrote {written}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
