"""``symloc experiment amcl-symmetric``: plain AMCL in symmetric rooms (the paper's Figure 8).

In each simulated room (square, triangle, pentagon, rectangle by default; closed, bare walls,
no furniture, as the paper's Gazebo rooms) the robot starts at a uniformly random pose, AMCL
starts from a uniform particle set (``initialize_global``), and the robot drives a short seeded
random path while the filter integrates odometry and scans. At the end each trial is
classified by the filter's estimate (the heaviest cluster):

* ``correct``: within ``--tol-xy`` [m] and ``--tol-deg`` of the true pose;
* ``symmetric_copy``: within the same tolerance of one of the true pose's k - 1 images under
  the room's rotational symmetry about its centre (k = order of the room);
* ``not_converged``: anything else.

``confident_wrong`` counts the trials whose estimate is not correct while the filter says it
is confident at the end, in the one sense of :mod:`symloc.mcl.confidence` (one dominant tight
hypothesis, the scan agrees with the map, sustained over 3 updates, and no rival place in the
map explains the recent scans as well). Columns kept for comparison:
``confident_wrong_without_rival_check`` (checks 1-4 of that definition only: what the filter
alone can know), ``confident_wrong_covariance_only`` (the earlier ad-hoc test: the heaviest
cluster's own covariance has position std < 0.3 m and heading std < 15 deg) and
``confident_wrong_nav2`` (the same test on the covariance of the whole particle set, which is
what nav2_amcl publishes). ``ambiguous`` counts trials whose final verdict is "ambiguous
place" (the rival search found another pose, typically the symmetric copy).

With a room of order k, AMCL can only pick one of k equally likely poses: about 1/k of the
trials should be correct. The scan agrees perfectly with the map at a symmetric copy, so
checks 1-4 cannot tell it from the truth and the filter alone is confidently wrong; only the
global rival search (check 5) sees that the place is ambiguous.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import as_rng
from symloc.cli import options
from symloc.experiments._common import (
    add_common_arguments,
    print_config,
    write_json,
    write_results_file,
)
from symloc.sim.rooms import ROOM_NAMES

__all__ = ["TrialResult", "classify", "register", "run", "run_room", "symmetric_images"]

FloatArray = NDArray[np.float64]

DEFAULT_ROOMS = ("square", "triangle", "pentagon", "rectangle")


@dataclass
class TrialResult:
    """One trial: true and estimated poses, class, reported uncertainty."""

    room: str
    true_pose: FloatArray
    estimate: FloatArray
    outcome: str
    copy_index: int
    std_xy: float
    std_theta: float
    std_xy_set: float
    std_theta_set: float
    n_hypotheses: int
    weight: float
    confident: bool = False
    confident_without_rival_check: bool = False
    confidence_reason: str = ""
    particles: FloatArray = field(repr=False, default_factory=lambda: np.zeros((0, 3)))
    weights: FloatArray = field(repr=False, default_factory=lambda: np.zeros(0))


def symmetric_images(pose: FloatArray, center: FloatArray, order: int) -> FloatArray:
    """The ``order`` images ``(k, 3)`` of ``pose`` under rotations by ``2 pi j / k`` about
    ``center`` (row 0 is the pose itself)."""
    k = max(int(order), 1)
    ang = 2.0 * np.pi * np.arange(k) / k
    c, s = np.cos(ang), np.sin(ang)
    d = np.asarray(pose[:2]) - np.asarray(center)
    out = np.empty((k, 3))
    out[:, 0] = center[0] + c * d[0] - s * d[1]
    out[:, 1] = center[1] + s * d[0] + c * d[1]
    out[:, 2] = np.pi - np.mod(np.pi - (pose[2] + ang), 2 * np.pi)
    return out


def classify(
    estimate: FloatArray, images: FloatArray, tol_xy: float, tol_theta: float
) -> tuple[str, int]:
    """``("correct", 0)``, ``("symmetric_copy", j)`` or ``("not_converged", -1)``."""
    dxy = np.hypot(images[:, 0] - estimate[0], images[:, 1] - estimate[1])
    dth = np.abs(np.pi - np.mod(np.pi - (images[:, 2] - estimate[2]), 2 * np.pi))
    ok = (dxy < tol_xy) & (dth < tol_theta)
    if ok[0]:
        return "correct", 0
    if ok.any():
        j = int(np.flatnonzero(ok)[np.argmin(dxy[ok])])
        return "symmetric_copy", j
    return "not_converged", -1


def _std_from_cov(cov: FloatArray) -> tuple[float, float]:
    ev = np.linalg.eigvalsh(cov[:2, :2])
    return float(math.sqrt(max(ev.max(), 0.0))), float(math.sqrt(max(cov[2, 2], 0.0)))


def _set_covariance(particles: FloatArray, weights: FloatArray) -> FloatArray:
    """Covariance of the whole particle set (what nav2 publishes), circular for theta."""
    w = weights / weights.sum()
    m = w @ particles[:, :2]
    d = particles[:, :2] - m
    cov = np.zeros((3, 3))
    cov[:2, :2] = (d * w[:, None]).T @ d
    r = math.hypot(float(w @ np.cos(particles[:, 2])), float(w @ np.sin(particles[:, 2])))
    cov[2, 2] = -2.0 * math.log(max(r, 1e-300))
    return cov


def _start_pose(room: Any, rng: np.random.Generator, margin: float) -> FloatArray:
    lo = room.boundary.min(axis=0)
    hi = room.boundary.max(axis=0)
    for _ in range(10000):
        xy = rng.uniform(lo, hi)
        if room.contains(xy[None])[0] and room.world.distance(xy[None])[0] >= margin:
            return np.array([xy[0], xy[1], rng.uniform(-np.pi, np.pi)])
    raise RuntimeError(f"cannot place the robot in room {room.name!r}")


def run_trial(
    room: Any,
    grid: Any,
    params: Any,
    preset: Any,
    rng: np.random.Generator,
    *,
    duration: float,
    scan_period: float,
    odom_alpha: float,
    tol_xy: float,
    tol_theta: float,
) -> TrialResult:
    """One global-localization trial in ``room`` (see the module docstring)."""
    from symloc.mcl import Amcl, ConfidenceJudge
    from symloc.sim.lidar import simulate_scan
    from symloc.sim.robot import DiffDriveRobot, OdometryNoise, RobotConfig

    start = _start_pose(room, rng, margin=0.4)
    noise = OdometryNoise(odom_alpha, odom_alpha, odom_alpha, odom_alpha)
    robot = DiffDriveRobot(start, RobotConfig(noise=noise), rng, world=room.world)
    amcl = Amcl(grid, params, rng)
    judge = ConfidenceJudge(amcl)  # the verdict, judged after every filter update
    amcl.initialize_global()
    dt = 0.1
    steps_per_scan = max(1, round(scan_period / dt))
    n_steps = max(1, round(duration / dt))
    v, w = 0.3, 0.0
    res, conf = judge.update(robot.odometry(), simulate_scan(room.world, robot.pose, preset, rng))
    turning = 0
    for i in range(n_steps):
        if i % 10 == 0 and turning == 0:
            w = float(rng.uniform(-0.8, 0.8))
        if turning > 0:
            ok = robot.step(0.0, 1.5, dt)
            turning -= 1
        else:
            ok = robot.step(v, w, dt)
            ahead = robot.pose
            ahead_pt = ahead[:2] + 0.35 * np.array([np.cos(ahead[2]), np.sin(ahead[2])])
            if not ok or room.world.distance(ahead_pt[None])[0] < robot.config.radius:
                turning = int(rng.integers(5, 15))
        if (i + 1) % steps_per_scan == 0:
            scan = simulate_scan(room.world, robot.pose, preset, rng, stamp=robot.time)
            res, conf = judge.update(robot.odometry(), scan)
    true = robot.pose
    images = symmetric_images(true, room.center, room.order if room.order > 1 else 1)
    outcome, j = classify(res.estimate, images, tol_xy, tol_theta)
    sxy, sth = _std_from_cov(res.covariance)
    sxy_set, sth_set = _std_from_cov(_set_covariance(res.particles, res.weights))
    return TrialResult(
        room=room.name,
        true_pose=true,
        estimate=res.estimate,
        outcome=outcome,
        copy_index=j,
        std_xy=sxy,
        std_theta=sth,
        std_xy_set=sxy_set,
        std_theta_set=sth_set,
        n_hypotheses=res.n_hypotheses,
        weight=res.weight,
        confident=bool(conf.confident),
        confident_without_rival_check=bool(conf.locally_confident),
        confidence_reason=conf.reason,
        particles=np.array(res.particles),
        weights=np.array(res.weights),
    )


def run_room(
    name: str,
    trials: int,
    rng: np.random.Generator | int | None,
    *,
    gv: float = 2.5,
    resolution: float = 0.05,
    params: Any = None,
    preset_name: str = "paper_15m",
    duration: float = 45.0,
    scan_period: float = 0.5,
    odom_alpha: float = 0.05,
    tol_xy: float = 0.3,
    tol_deg: float = 10.0,
    confident_xy: float = 0.3,
    confident_deg: float = 15.0,
    progress: bool = True,
) -> tuple[dict[str, Any], list[TrialResult], Any]:
    """Run ``trials`` trials in one room; returns (summary dict, trials, grid).

    ``confident_xy`` / ``confident_deg`` only define the legacy ``*_covariance_only`` and
    ``*_nav2`` columns; ``confident_wrong`` uses :mod:`symloc.mcl.confidence`.
    """
    from tqdm import tqdm

    from symloc.mcl import AmclParams
    from symloc.sim.lidar import PRESETS
    from symloc.sim.rasterize import world_to_grid
    from symloc.sim.rooms import build_room

    gen = as_rng(rng)
    room = build_room(name, gv, lab=False, textured=False)
    grid = world_to_grid(room.world, resolution)
    p = AmclParams() if params is None else params
    preset = PRESETS[preset_name]
    tol_th = math.radians(tol_deg)
    out: list[TrialResult] = []
    for _ in tqdm(range(trials), desc=f"amcl {name}", disable=not progress, leave=False):
        out.append(
            run_trial(
                room,
                grid,
                p,
                preset,
                gen,
                duration=duration,
                scan_period=scan_period,
                odom_alpha=odom_alpha,
                tol_xy=tol_xy,
                tol_theta=tol_th,
            )
        )
    conf = [t.confident for t in out]
    conf_norival = [t.confident_without_rival_check for t in out]
    conf_cov = [t.std_xy < confident_xy and t.std_theta < math.radians(confident_deg) for t in out]
    conf_set = [
        t.std_xy_set < confident_xy and t.std_theta_set < math.radians(confident_deg) for t in out
    ]
    wrong = [t.outcome != "correct" for t in out]
    n = len(out)
    k = room.order
    summary: dict[str, Any] = {
        "room": name,
        "order": int(k),
        "expected_correct_rate": 1.0 / k if k >= 1 else None,
        "trials": n,
        "correct": sum(t.outcome == "correct" for t in out),
        "symmetric_copy": sum(t.outcome == "symmetric_copy" for t in out),
        "not_converged": sum(t.outcome == "not_converged" for t in out),
        "confident_wrong": int(sum(c and w for c, w in zip(conf, wrong, strict=True))),
        "confident_wrong_without_rival_check": int(
            sum(c and w for c, w in zip(conf_norival, wrong, strict=True))
        ),
        "confident_wrong_covariance_only": int(
            sum(c and w for c, w in zip(conf_cov, wrong, strict=True))
        ),
        "confident_wrong_nav2": int(sum(c and w for c, w in zip(conf_set, wrong, strict=True))),
        "confident_correct": int(sum(c and not w for c, w in zip(conf, wrong, strict=True))),
        "confident_correct_without_rival_check": int(
            sum(c and not w for c, w in zip(conf_norival, wrong, strict=True))
        ),
        "ambiguous": sum(t.confidence_reason.startswith("ambiguous place") for t in out),
    }
    wrong_t = [t for t in out if t.outcome != "correct"]
    summary["correct_rate"] = summary["correct"] / n if n else 0.0
    summary["wrong_std_xy_median_m"] = (
        float(np.median([t.std_xy for t in wrong_t])) if wrong_t else None
    )
    summary["wrong_std_theta_median_deg"] = (
        float(np.degrees(np.median([t.std_theta for t in wrong_t]))) if wrong_t else None
    )
    summary["wrong_n_hypotheses_median"] = (
        float(np.median([t.n_hypotheses for t in wrong_t])) if wrong_t else None
    )
    summary["n_hypotheses_histogram"] = {
        str(h): int(c)
        for h, c in zip(*np.unique([t.n_hypotheses for t in out], return_counts=True), strict=True)
    }
    return summary, out, grid


def register(subparsers: Any) -> None:
    """Add ``amcl-symmetric`` to ``symloc experiment``."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "amcl-symmetric",
        help="plain AMCL global localization in symmetric rooms (paper Figure 8, measured)",
    )
    add_common_arguments(parser, "amcl-symmetric")
    options.add_trials(parser, default=200, what="trials per room")
    options.add_rooms(parser, rooms=DEFAULT_ROOMS, choices=ROOM_NAMES)
    parser.add_argument("--gv", type=options.gv_distance, default=2.5, help="room G-V distance [m]")
    parser.add_argument(
        "--duration", type=options.sim_seconds, default=45.0, help="path length [s] at 0.3 m/s"
    )
    options.add_lidar(parser, help="simulated lidar (the paper's Figure 8: paper_15m)")
    parser.add_argument(
        "--max-particles", type=options.particles, default=2000, help="nav2 max_particles"
    )
    parser.add_argument(
        "--min-particles", type=options.particles, default=500, help="nav2 min_particles"
    )
    parser.add_argument(
        "--params", default=None, metavar="YAML", help="nav2 params file (amcl block) to use"
    )
    parser.add_argument(
        "--odom-alpha",
        type=options.nonnegative_float,
        default=0.05,
        help="robot odometry noise alpha1..4",
    )
    parser.add_argument(
        "--amcl-alpha",
        type=options.nonnegative_float,
        default=None,
        help="AMCL alpha1..4 (default: equal to --odom-alpha, i.e. matched to the robot)",
    )
    parser.add_argument(
        "--laser-model",
        default="likelihood_field",
        choices=["likelihood_field", "likelihood_field_prob", "beam"],
        help="nav2 laser_model_type (default nav2's likelihood_field)",
    )
    options.add_results(
        parser,
        "docs/results/amcl_symmetric.json",
        note="; with --laser-model likelihood_field_prob: "
        "docs/results/amcl_symmetric_likelihood_field_prob.json",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the experiment, print the table, write the JSON and the figure."""
    from symloc.mcl import AmclParams

    params = (
        AmclParams.from_nav2_yaml(args.params)
        if args.params
        else AmclParams(
            max_particles=args.max_particles,
            min_particles=args.min_particles,
            laser_model_type=args.laser_model,
            **dict.fromkeys(
                ("alpha1", "alpha2", "alpha3", "alpha4"),
                args.odom_alpha if args.amcl_alpha is None else args.amcl_alpha,
            ),
        )
    )
    config = {
        "seed": args.seed,
        "trials": args.trials,
        "rooms": ", ".join(options.room_names(args.rooms, DEFAULT_ROOMS)),
        "gv_distance_m": args.gv,
        "path": f"{args.duration:g} s random drive at 0.3 m/s, scans at 2 Hz",
        "lidar": args.lidar,
        "odometry noise alphas": args.odom_alpha,
        "amcl": f"nav2 defaults except max/min particles {params.max_particles}/"
        f"{params.min_particles}, {params.laser_model_type}, alpha1..4 = {params.alpha1}",
        "laser_model_type": params.laser_model_type,
        "correct": "within 0.3 m and 10 deg",
        "confident": "symloc.mcl.confidence defaults (dominant tight hypothesis, scan"
        " consistency, 3-update hysteresis, no rival place); legacy columns: std < 0.3 m"
        " and < 15 deg of the cluster (cov only) / of the whole set (nav2)",
    }
    print_config("amcl-symmetric", config)
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    rng = np.random.default_rng(args.seed)
    summaries = []
    examples = {}
    for name in options.room_names(args.rooms, DEFAULT_ROOMS):
        summary, trials, grid = run_room(
            name,
            args.trials,
            rng,
            gv=args.gv,
            params=params,
            preset_name=args.lidar,
            duration=args.duration,
            odom_alpha=args.odom_alpha,
        )
        summaries.append(summary)
        pick = next((t for t in trials if t.outcome == "symmetric_copy"), trials[0])
        examples[name] = (grid, pick)
    print()
    print(
        f"{'room':<10} {'k':>2} {'trials':>6} {'correct':>8} {'1/k':>5} {'sym.copy':>8}"
        f" {'not conv':>8} {'conf.wrong':>10} {'(no rival)':>10} {'(cov only)':>10}"
        f" {'(nav2 cov)':>10} {'ambiguous':>9} {'conf.corr':>9} {'wrong std xy/deg':>17}"
    )
    for s in summaries:
        sxy = s["wrong_std_xy_median_m"]
        sth = s["wrong_std_theta_median_deg"]
        std_s = f"{sxy:.3f}/{sth:.1f}" if sxy is not None else "-"
        print(
            f"{s['room']:<10} {s['order']:>2} {s['trials']:>6} {s['correct_rate']:>8.2f}"
            f" {s['expected_correct_rate']:>5.2f} {s['symmetric_copy']:>8} {s['not_converged']:>8}"
            f" {s['confident_wrong']:>10} {s['confident_wrong_without_rival_check']:>10}"
            f" {s['confident_wrong_covariance_only']:>10} {s['confident_wrong_nav2']:>10}"
            f" {s['ambiguous']:>9} {s['confident_correct']:>9} {std_s:>17}"
        )
    from symloc.figures.mcl import amcl_symmetric_figure

    path = amcl_symmetric_figure(summaries, examples, args.out / "amcl_symmetric.png")
    print(f"wrote {path}")
    write_json(
        args.json,
        {
            "seed": args.seed,
            "config": {
                "trials": args.trials,
                "gv": args.gv,
                "duration_s": args.duration,
                "lidar": args.lidar,
                "odom_alpha": args.odom_alpha,
                "laser_model_type": params.laser_model_type,
                "amcl_alpha": params.alpha1,
                "max_particles": params.max_particles,
                "min_particles": params.min_particles,
            },
            "rooms": summaries,
        },
    )
    write_results_file(args, clock, config, {"rooms": summaries})
    return 0
