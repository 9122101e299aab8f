"""``symloc experiment amcl-carmen``: AMCL on real CARMEN laser logs.

For each log in ``../shared/data/carmen/`` (intel, aces, freiburg-079):

1. the map is built from the corrected poses (``symloc.grid.log_odds.LogOddsGrid``, 5 cm);
2. **tracking**: the odometry is the corrected trajectory corrupted by odometry noise (the
   corrected logs carry no raw odometry: their ``odom_*`` fields equal the corrected poses), as
   a differential drive with ``alpha1..alpha4`` (Thrun et al. Table 5.6, the simulator's
   ``OdometryNoise``) would report it; AMCL starts from the true first pose (covariance nav2's
   default) and its pose is compared with the corrected pose at every scan (between filter
   updates the pose is the last estimate moved by the odometry, as nav2's map->odom transform
   gives it);
3. **global localization**: from ``--starts`` random scans of the log, AMCL starts from a
   uniform particle set over the map's free cells and runs for up to ``--window`` scans. A
   start converges when the estimate comes within 0.3 m and 10 degrees of the corrected pose
   and stays there for the rest of the window; we report how often, after how many scans /
   metres, and whether the filter ever reported a *confident wrong* pose: confident in the
   sense of :mod:`symloc.mcl.confidence` (one dominant tight hypothesis whose scan agrees with
   the map, sustained over 3 updates) while more than 1 m or 30 degrees off
   (``confident_wrong``), or merely outside the 0.3 m / 10 degree tolerance
   (``confident_outside_tolerance``). The previous ad-hoc definition (a single well-weighted
   hypothesis, ``n_hypotheses == 1``, with position std < 0.3 m and heading std < 15 degrees)
   is still counted as ``*_covariance_only`` for comparison.

Beside plain AMCL, **symloc** runs on the same scans and odometry: the
:class:`~symloc.localizer.Localizer` with its claim gate (:mod:`symloc.localizer.claim`), which
publishes a pose as tracking only when the laser confirms it at that scan. Its claims are graded
against the corrected poses: *confident wrong* beyond 1 m or 30 degrees, *outside the
tolerance* beyond 0.1 m or 5 degrees; for each claim outside the tolerance the scan's fit to the
map (share of beams within 0.1 m of a surface) is measured at the claimed and at the reference
pose, so that a reference that lags (a corrected pose that fits the scan worse than the claim)
is told apart from a claim that is wrong.
"""

from __future__ import annotations

import argparse
import logging
import math
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import as_rng
from symloc.bench.carmen_tracking import (
    log_stream,
    noisy_odometry,
    tracking_odometry,
    tracking_stream,
)
from symloc.bench.shared_data import CARMEN_LOGS as LOG_NAMES
from symloc.bench.shared_data import carmen_log_paths, find_carmen_dir
from symloc.cli import options
from symloc.experiments._common import (
    add_common_arguments,
    print_config,
    write_json,
    write_results_file,
)
from symloc.files.atomic import atomic_path
from symloc.geometry import compose, inverse, wrap_angle
from symloc.io.rosbag_carmen import START_COVARIANCE
from symloc.localizer.settings import LocalizerSettings

__all__ = [
    "LOG_NAMES",
    "amcl_tracking_error",
    "build_map",
    "find_carmen_dir",
    "global_localization",
    "log_data",
    "noisy_odometry",
    "register",
    "run",
    "tracking",
    "tracking_odometry",
    "tracking_params",
    "tracking_stream",
]

FloatArray = NDArray[np.float64]

logger = logging.getLogger(__name__)


def build_map(log: Any, resolution: float = 0.05, cache: Path | None = None) -> Any:
    """Occupancy grid from the log's scans at their corrected poses.

    With ``cache`` (an ``.npz`` path) the grid is loaded from there if it was built from this
    log at this resolution by this version of the builder (:func:`_map_key`), else built and
    saved there: a folder reused across versions must not hand a stale map to a new run.
    """
    from symloc.grid import OccupancyGrid
    from symloc.grid.log_odds import LogOddsGrid

    key = _map_key(log, resolution) if cache is not None else ""
    if cache is not None and cache.is_file():
        try:
            with np.load(cache) as z:
                if "key" in z.files and str(z["key"]) == key:
                    return OccupancyGrid(z["data"], float(z["resolution"]), z["origin"])
            logger.info("%s: built for another log, resolution or builder; building anew", cache)
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as err:
            logger.warning("%s: not a readable map cache (%s); building anew", cache, err)
    lo = LogOddsGrid(resolution)
    for s in log.scans:
        lo.integrate(s.laser_pose, s.scan)
    grid = lo.to_occupancy_grid()
    if cache is not None:
        with atomic_path(cache) as tmp:
            np.savez_compressed(
                tmp,
                data=grid.data,
                resolution=grid.resolution,
                origin=np.asarray(grid.origin),
                key=np.asarray(key),
            )
    return grid


#: Bumped whenever :func:`build_map` would draw another grid from the same log.
MAP_BUILDER_VERSION = 2


def _map_key(log: Any, resolution: float) -> str:
    """What a cached map must have been built from: the builder's version, the resolution and
    a fingerprint of the log's scans (count, first and last stamp, and the sum of their
    poses and ranges)."""
    scans = log.scans
    n = len(scans)
    if n == 0:
        return f"v{MAP_BUILDER_VERSION}|{resolution!r}|0"
    poses = float(sum(float(np.sum(s.laser_pose)) for s in scans))
    ranges = float(sum(float(np.sum(s.scan.ranges)) for s in scans))
    return (
        f"v{MAP_BUILDER_VERSION}|{resolution!r}|{n}|{scans[0].stamp!r}|{scans[-1].stamp!r}"
        f"|{poses!r}|{ranges!r}"
    )


def tracking_params(
    alpha: float = 0.01,
    *,
    laser_model: str = "likelihood_field_prob",
    particles: int = 2000,
) -> Any:
    """The AMCL parameters of this experiment's tracking: nav2's defaults except
    ``laser_model``, ``alpha1..4 = alpha`` (the variances the odometry noise is drawn with),
    ``max_particles = particles`` (``min_particles`` at most 500) and a laser max range of
    49.9 m (the logs' 50 m readings are no-returns). ``symloc replay`` with
    ``src/symloc/ros/examples/carmen_params.yaml`` builds the same localizer settings
    (:func:`carmen_settings`; a test holds the two together)."""
    from symloc.mcl import AmclParams

    return AmclParams(
        laser_model_type=laser_model,
        alpha1=alpha,
        alpha2=alpha,
        alpha3=alpha,
        alpha4=alpha,
        laser_max_range=49.9,
        max_particles=particles,
        min_particles=min(500, particles),
    )


def _errors(est: FloatArray, truth: FloatArray) -> tuple[FloatArray, FloatArray]:
    dxy = np.hypot(est[:, 0] - truth[:, 0], est[:, 1] - truth[:, 1])
    dth = np.abs(wrap_angle(est[:, 2] - truth[:, 2]))
    return dxy, np.atleast_1d(dth)


def _run_filter(amcl: Any, log: Any, odom: FloatArray, start: int, stop: int) -> dict[str, Any]:
    """Feed scans ``start..stop-1``; per scan the pose estimate and the filter's confidence
    (judged after each update by a :class:`~symloc.mcl.confidence.ConfidenceJudge`)."""
    from symloc.mcl.confidence import ConfidenceJudge
    from symloc.odometry import OdometryReading

    judge = ConfidenceJudge(amcl)

    n = stop - start
    est = np.empty((n, 3))
    conf = np.zeros(n, dtype=bool)
    conf_cov = np.zeros(n, dtype=bool)
    nh = np.zeros(n, dtype=np.int64)
    share = np.zeros(n)
    std = np.zeros((n, 2))
    cons = np.full(n, np.nan)
    checks = np.zeros(n, dtype=bool)
    reasons: list[str] = []
    last_est: FloatArray | None = None
    last_odom: FloatArray = odom[start]
    for k, i in enumerate(range(start, stop)):
        res, c = judge.update(OdometryReading(odom[i], log.scans[i].stamp), log.scans[i].scan)
        if res.updated or last_est is None:
            last_est, last_odom = res.estimate, odom[i]
        # nav2's map->odom: the last estimate moved by the odometry since that update
        est[k] = compose(last_est, compose(inverse(last_odom), odom[i]))
        conf[k] = c.confident
        checks[k] = c.checks_pass
        reasons.append(c.reason)
        share[k] = c.weight_share
        std[k] = c.std_xy, c.std_theta
        cons[k] = c.scan_consistency
        # the previous ad-hoc definition, kept for comparison
        conf_cov[k] = res.n_hypotheses == 1 and c.std_xy < 0.3 and c.std_theta < math.radians(15)
        nh[k] = res.n_hypotheses
    return {
        "estimate": est,
        "confident": conf,
        "confident_covariance_only": conf_cov,
        "checks_pass": checks,
        "weight_share": share,
        "std": std,
        "scan_consistency": cons,
        "n_hypotheses": nh,
        "reason": reasons,
    }


def _fit(field: Any, pose: FloatArray, scan: Any) -> float:
    """Share of the scan's returning beams within 0.1 m of a map surface at ``pose``."""
    from symloc.mcl.beams import select_beams
    from symloc.mcl.scan_to_map import scan_points

    b = select_beams(scan, max(len(scan), 2))
    pts = scan_points(b.ranges[b.hit], b.angles[b.hit], (0.0, 0.0, 0.0))
    if pts.shape[0] == 0:
        return math.nan
    c, s = math.cos(pose[2]), math.sin(pose[2])
    world = np.column_stack(
        [pose[0] + c * pts[:, 0] - s * pts[:, 1], pose[1] + s * pts[:, 0] + c * pts[:, 1]]
    )
    return float(np.mean(np.abs(field.lookup(world)) <= 0.1))


def carmen_settings(params: Any) -> LocalizerSettings:
    """The localizer's settings on a CARMEN log: AMCL with ``params``, and the claim gate's
    odometry error model = AMCL's alphas (the logs' odometry is this experiment's own noisy
    odometry, drawn with those alphas; :attr:`ClaimConfig.odometry_alphas`). No images, so no
    visual map (a :class:`~symloc.localizer.places.MemoryPlaces`); Algorithm 1 with
    :class:`~symloc.symmetry.SymmetryConfig`'s defaults; the rest as the node's defaults."""
    from symloc.localizer.claim import ClaimConfig

    alphas = (params.alpha1, params.alpha2, params.alpha3, params.alpha4)
    return LocalizerSettings(amcl=params, claim=ClaimConfig(odometry_alphas=alphas))


def symloc_claims(
    data: _LogData,
    params: Any,
    odom: FloatArray,
    start: int,
    stop: int,
    rng: np.random.Generator,
    *,
    known_start: bool,
) -> dict[str, Any]:
    """symloc's localizer over scans ``start..stop-1``: what it publishes as tracking, graded.

    ``known_start`` gives it the corrected first pose (tracking); else it starts lost (global).
    """
    from symloc.grid.fields import surface_distance_field
    from symloc.localizer import Status
    from symloc.localizer.build import build_localizer
    from symloc.odometry import OdometryReading

    field = surface_distance_field(data.grid)
    loc = build_localizer(data.grid, carmen_settings(params), rng=rng)
    if known_start:
        loc.set_pose(data.truth[start], START_COVARIANCE)
    else:
        loc.reset_global()
    n = stop - start
    claims = np.full((n, 3), np.nan)
    for k, i in enumerate(range(start, stop)):
        scan = data.log.scans[i]
        est = loc.update(OdometryReading(odom[i], scan.stamp), scan.scan)
        if est.status is Status.TRACKING and est.pose is not None:
            claims[k] = est.pose
    claimed = np.isfinite(claims[:, 0])
    truth = data.truth[start:stop]
    dxy = np.full(n, np.nan)
    dth = np.full(n, np.nan)
    if claimed.any():
        dxy[claimed], dth[claimed] = _errors(claims[claimed], truth[claimed])
    outside = claimed & ((dxy > 0.1) | (dth > math.radians(5.0)))
    gross = claimed & ((dxy > 1.0) | (dth > math.radians(30.0)))
    causes = []
    for j in np.flatnonzero(outside).tolist():
        scan = data.log.scans[start + j].scan
        at_claim, at_ref = _fit(field, claims[j], scan), _fit(field, truth[j], scan)
        causes.append(
            {
                "scan": int(start + j),
                "error_m": float(dxy[j]),
                "heading_error_deg": float(np.degrees(dth[j])),
                "fit_at_claim": at_claim,
                "fit_at_reference": at_ref,
                "reference_fits_worse": bool(at_ref < at_claim),
            }
        )
    return {
        "scans": int(n),
        "claimed_scans": int(claimed.sum()),
        "first_claim": int(np.flatnonzero(claimed)[0]) if claimed.any() else None,
        "mean_error_m": float(np.nanmean(dxy)) if claimed.any() else None,
        "p95_error_m": float(np.nanpercentile(dxy, 95)) if claimed.any() else None,
        "p95_heading_error_deg": float(np.degrees(np.nanpercentile(dth, 95)))
        if claimed.any()
        else None,
        "confident_wrong_scans": int(gross.sum()),
        "outside_tolerance_scans": int(outside.sum()),
        "outside_tolerance_reference_fits_worse": int(
            sum(c["reference_fits_worse"] for c in causes)
        ),
        "outside_tolerance": causes,
    }


@dataclass
class _LogData:
    name: str
    log: Any
    grid: Any
    truth: FloatArray


def tracking(data: _LogData, params: Any, alphas: tuple[float, ...], rng: Any) -> dict[str, Any]:
    """Tracking from the true initial pose along the whole log."""
    from symloc.mcl import Amcl

    gen = as_rng(rng)
    odom = noisy_odometry(data.truth, alphas, gen)  # type: ignore[arg-type]
    amcl = Amcl(data.grid, params, gen)
    amcl.initialize_pose(data.truth[0])
    out = _run_filter(amcl, data.log, odom, 0, len(data.truth))
    dxy, dth = _errors(out["estimate"], data.truth)
    odo_xy, _ = _errors(odom, data.truth)
    sy = symloc_claims(data, params, odom, 0, len(data.truth), gen, known_start=True)
    return {
        "symloc": sy,
        "scans": len(dxy),
        "mean_error_m": float(dxy.mean()),
        "median_error_m": float(np.median(dxy)),
        "p95_error_m": float(np.percentile(dxy, 95)),
        "max_error_m": float(dxy.max()),
        "mean_heading_error_deg": float(np.degrees(dth.mean())),
        "max_heading_error_deg": float(np.degrees(dth.max())),
        "odometry_only_mean_error_m": float(odo_xy.mean()),
        "odometry_only_final_error_m": float(odo_xy[-1]),
        "skipped_scans": int(amcl.n_scans_skipped),
        "_estimate": out["estimate"],
    }


def log_data(name: str, path: Path, cache: Path | None = None) -> _LogData:
    """Log ``name`` read from ``path`` as the experiment reads it: its scans, the map drawn
    from the corrected poses (:func:`build_map`, kept in ``cache``) and the corrected poses
    with wrapped headings as the truth."""
    from symloc.io.carmen import read_carmen

    log = read_carmen(path)
    grid = build_map(log, cache=cache)
    truth = log.laser_poses.copy()
    truth[:, 2] = wrap_angle(truth[:, 2])
    return _LogData(name, log, grid, truth)


def amcl_tracking_error(
    data: _LogData,
    seed: int,
    alpha: float = 0.01,
    **overrides: Any,
) -> dict[str, float]:
    """AMCL alone tracking ``data``'s log as this experiment's tracking does with ``--seed
    seed --odom-alpha alpha`` (the same odometry draw and random stream,
    :func:`tracking_stream`; the same AMCL parameters,
    :func:`tracking_params` with its default laser model and particles), with ``overrides`` of those parameters (e.g. ``update_min_d=0``,
    ``alpha1=0.04``): the mean, median and largest position error [m] over the scans. Without
    overrides the mean is the experiment's ``mean_error_m``; the confidence verdict and
    symloc's claims are not run."""
    from symloc.mcl import Amcl

    gen = tracking_stream(data.name, seed)
    odom = noisy_odometry(data.truth, (alpha,) * 4, gen)
    amcl = Amcl(data.grid, tracking_params(alpha).replace(**overrides), gen)
    amcl.initialize_pose(data.truth[0])
    out = _run_filter(amcl, data.log, odom, 0, len(data.truth))
    dxy, _ = _errors(out["estimate"], data.truth)
    return {
        "mean_error_m": float(dxy.mean()),
        "median_error_m": float(np.median(dxy)),
        "max_error_m": float(dxy.max()),
    }


def global_localization(
    data: _LogData,
    params: Any,
    alphas: tuple[float, ...],
    rng: Any,
    *,
    starts: int,
    window: int,
    progress: bool = True,
    trace: list[dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """Global localization from ``starts`` random scans; see the module docstring.

    With ``trace`` (a list) each start's per-scan errors and confidence terms are appended.
    """
    from tqdm import tqdm

    from symloc.mcl import Amcl

    gen = as_rng(rng)
    t = len(data.truth)
    odom = noisy_odometry(data.truth, alphas, gen)  # type: ignore[arg-type]
    first = gen.choice(max(t - 10, 1), size=min(starts, max(t - 10, 1)), replace=False)
    # each start's AMCL and symloc draw from streams of their own: one method's figures must
    # not depend on how many numbers the other drew (they shared one stream until 2026-11-28,
    # and a change to symloc's claim gate moved AMCL's convergence on aces from 14 to 5 of 20)
    streams = gen.integers(0, 2**63, size=(len(first), 2))
    runs: list[dict[str, Any]] = []
    tol_xy, tol_th = 0.3, math.radians(10.0)
    for k, s in enumerate(
        tqdm(sorted(first.tolist()), desc=f"global {data.name}", disable=not progress, leave=False)
    ):
        stop = min(t, s + window)
        amcl = Amcl(data.grid, params, np.random.default_rng(int(streams[k, 0])))
        amcl.initialize_global()
        out = _run_filter(amcl, data.log, odom, s, stop)
        dxy, dth = _errors(out["estimate"], data.truth[s:stop])
        ok = (dxy < tol_xy) & (dth < tol_th)
        # converged at the first scan after which it stays within tolerance
        bad = np.flatnonzero(~ok)
        conv_at = 0 if bad.size == 0 else int(bad[-1] + 1)
        converged = conv_at < len(ok)
        gross = (dxy > 1.0) | (dth > math.radians(30.0))
        cc = out["confident_covariance_only"]
        first_conf = np.flatnonzero(out["confident"])
        path = np.concatenate(
            [[0.0], np.cumsum(np.hypot(*np.diff(data.truth[s:stop, :2], axis=0).T))]
        )
        runs.append(
            {
                "start_scan": int(s),
                "scans": int(stop - s),
                "converged": bool(converged),
                "scans_to_converge": int(conv_at) if converged else None,
                "metres_to_converge": float(path[conv_at]) if converged else None,
                "seconds_to_converge": float(
                    data.log.scans[s + conv_at].stamp - data.log.scans[s].stamp
                )
                if converged
                else None,
                "confident_wrong_scans": int(np.count_nonzero(out["confident"] & gross)),
                "confident_outside_tolerance_scans": int(np.count_nonzero(out["confident"] & ~ok)),
                "confident_scans": int(np.count_nonzero(out["confident"])),
                "max_error_while_confident_m": float(dxy[out["confident"]].max())
                if out["confident"].any()
                else None,
                "max_heading_error_while_confident_deg": float(
                    np.degrees(dth[out["confident"]].max())
                )
                if out["confident"].any()
                else None,
                "scans_to_confident": int(first_conf[0]) if first_conf.size else None,
                "confident_at_end": bool(out["confident"][-1]),
                "confident_wrong_scans_covariance_only": int(np.count_nonzero(cc & gross)),
                "confident_outside_tolerance_scans_covariance_only": int(
                    np.count_nonzero(cc & ~ok)
                ),
                "final_error_m": float(dxy[-1]),
            }
        )
        runs[-1]["symloc"] = symloc_claims(
            data,
            params,
            odom,
            s,
            stop,
            np.random.default_rng(int(streams[k, 1])),
            known_start=False,
        )
        if trace is not None:
            trace.append({"start_scan": int(s), "dxy": dxy, "dth": dth, **out})
    conv = [r for r in runs if r["converged"]]
    return {
        "starts": len(runs),
        "window_scans": window,
        "converged": len(conv),
        "median_scans_to_converge": float(np.median([r["scans_to_converge"] for r in conv]))
        if conv
        else None,
        "median_metres_to_converge": float(np.median([r["metres_to_converge"] for r in conv]))
        if conv
        else None,
        "runs_with_confident_wrong": int(sum(r["confident_wrong_scans"] > 0 for r in runs)),
        "confident_wrong_scans": sum(int(r["confident_wrong_scans"]) for r in runs),
        "runs_with_confident_outside_tolerance": int(
            sum(r["confident_outside_tolerance_scans"] > 0 for r in runs)
        ),
        "runs_confident": int(sum(r["confident_scans"] > 0 for r in runs)),
        "max_error_while_confident_m": max(
            (r["max_error_while_confident_m"] for r in runs if r["confident_scans"]),
            default=None,
        ),
        "max_heading_error_while_confident_deg": max(
            (r["max_heading_error_while_confident_deg"] for r in runs if r["confident_scans"]),
            default=None,
        ),
        "runs_confident_at_end": int(sum(r["confident_at_end"] for r in runs)),
        "runs_converged_and_confident_at_end": int(
            sum(r["confident_at_end"] and r["converged"] for r in runs)
        ),
        "median_scans_to_confident": float(
            np.median(
                [r["scans_to_confident"] for r in runs if r["scans_to_confident"] is not None]
            )
        )
        if any(r["scans_to_confident"] is not None for r in runs)
        else None,
        "runs_with_confident_wrong_covariance_only": int(
            sum(r["confident_wrong_scans_covariance_only"] > 0 for r in runs)
        ),
        "symloc_runs_claimed": int(sum(r["symloc"]["claimed_scans"] > 0 for r in runs)),
        "symloc_runs_claimed_correctly_at_end": int(
            sum(
                r["symloc"]["claimed_scans"] > 0 and r["symloc"]["outside_tolerance_scans"] == 0
                for r in runs
            )
        ),
        "symloc_runs_confident_wrong": int(
            sum(r["symloc"]["confident_wrong_scans"] > 0 for r in runs)
        ),
        "symloc_runs_outside_tolerance": int(
            sum(r["symloc"]["outside_tolerance_scans"] > 0 for r in runs)
        ),
        "symloc_outside_tolerance_scans": int(
            sum(r["symloc"]["outside_tolerance_scans"] for r in runs)
        ),
        "symloc_outside_tolerance_reference_fits_worse": int(
            sum(r["symloc"]["outside_tolerance_reference_fits_worse"] for r in runs)
        ),
        "runs": runs,
    }


def register(subparsers: Any) -> None:
    """Add ``amcl-carmen`` to ``symloc experiment``."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "amcl-carmen",
        help="AMCL tracking and global localization on the CARMEN logs (map from corrected poses)",
    )
    add_common_arguments(parser, "amcl-carmen")
    parser.add_argument("--logs", nargs="+", default=list(LOG_NAMES), help="log names")
    parser.add_argument("--data", type=Path, default=None, help="folder with the CARMEN logs")
    parser.add_argument(
        "--starts", type=options.count, default=20, help="global-localization starts"
    )
    parser.add_argument("--window", type=options.count, default=100, help="scans per global start")
    parser.add_argument(
        "--odom-alpha",
        type=options.nonnegative_float,
        default=0.01,
        help="odometry noise alpha1..4 (10%% std)",
    )
    parser.add_argument(
        "--laser-model",
        default="likelihood_field_prob",
        choices=["likelihood_field", "likelihood_field_prob", "beam"],
        help="nav2 laser_model_type (default likelihood_field_prob)",
    )
    parser.add_argument(
        "--tracking-particles", type=options.particles, default=2000, help="max_particles"
    )
    parser.add_argument(
        "--global-particles", type=options.particles, default=20000, help="max_particles"
    )
    parser.add_argument(
        "--global-exponent",
        type=options.positive_float,
        default=1.0,
        help="laser_likelihood_exponent for global localization (1 = nav2's likelihood)",
    )
    parser.add_argument("--skip-global", action="store_true", help="tracking only")
    options.add_results(parser, "docs/results/amcl_carmen.json")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the experiment on each log; print, write JSON and the figure."""
    paths = carmen_log_paths(args.logs, args.data)
    folder = next(iter(paths.values())).parent
    a = args.odom_alpha
    alphas = (a, a, a, a)
    track_p = tracking_params(a, laser_model=args.laser_model, particles=args.tracking_particles)
    glob_p = tracking_params(
        a, laser_model=args.laser_model, particles=args.global_particles
    ).replace(
        recovery_alpha_slow=0.001,
        recovery_alpha_fast=0.1,
        laser_likelihood_exponent=args.global_exponent,
    )
    config = {
        "seed": args.seed,
        "data": str(folder),
        "logs": ", ".join(args.logs),
        "map": "log-odds grid at 0.05 m from the corrected poses",
        "odometry": f"corrected increments + rot-trans-rot noise, alpha1..4 = {a}",
        "amcl": f"nav2 defaults except {args.laser_model}, alpha1..4 = {a},"
        f" tracking {track_p.max_particles}/{track_p.min_particles} particles,"
        f" global {glob_p.max_particles}/{glob_p.min_particles} + recovery 0.001/0.1,"
        f" global likelihood exponent {glob_p.laser_likelihood_exponent}",
        "global": f"{args.starts} starts x up to {args.window} scans; converged = within"
        " 0.3 m / 10 deg to the end; confident = symloc.mcl.confidence defaults"
        " (dominant tight hypothesis, scan consistency, 3-update hysteresis, no rival"
        " place); wrong = error > 1 m or 30 deg",
    }
    print_config("amcl-carmen", config)
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    results: list[dict[str, Any]] = []
    fig_logs: list[dict[str, Any]] = []
    global_traces: list[dict[str, Any]] = []
    for name in args.logs:
        # independent streams per log and task, so one log's numbers do not depend on the others
        rng_track = log_stream(name, args.seed, "tracking")
        rng_global = log_stream(name, args.seed, "global")
        data = log_data(name, paths[name], cache=args.out / f"amcl_carmen_map_{name}.npz")
        log, grid, truth = data.log, data.grid, data.truth
        tr = tracking(data, track_p, alphas, rng_track)
        est = tr.pop("_estimate")
        entry: dict[str, Any] = {"log": name, "scans": len(truth), "tracking": tr}
        sy = tr["symloc"]
        print(
            f"{name}: symloc tracking claims {sy['claimed_scans']}/{sy['scans']} scans, mean"
            f" error {sy['mean_error_m']} m, p95 {sy['p95_error_m']} m /"
            f" {sy['p95_heading_error_deg']} deg; outside 0.1 m / 5 deg:"
            f" {sy['outside_tolerance_scans']} scans ({sy['outside_tolerance_reference_fits_worse']}"
            f" where the reference fits the scan worse); confident wrong (> 1 m / 30 deg):"
            f" {sy['confident_wrong_scans']}"
        )
        print(
            f"{name}: tracking mean {tr['mean_error_m']:.3f} m (median {tr['median_error_m']:.3f},"
            f" p95 {tr['p95_error_m']:.3f}, max {tr['max_error_m']:.3f}),"
            f" heading mean {tr['mean_heading_error_deg']:.2f} deg;"
            f" odometry alone {tr['odometry_only_mean_error_m']:.2f} m mean"
        )
        if not args.skip_global:
            trace: list[dict[str, Any]] = []
            gl = global_localization(
                data,
                glob_p,
                alphas,
                rng_global,
                starts=args.starts,
                window=args.window,
                trace=trace,
            )
            global_traces.append({"name": name, "trace": trace})
            entry["global"] = gl
            print(
                f"{name}: global {gl['converged']}/{gl['starts']} converged, median"
                f" {gl['median_scans_to_converge']} scans / {gl['median_metres_to_converge']} m;"
                f" runs with a confident wrong pose: {gl['runs_with_confident_wrong']}"
                f" ({gl['confident_wrong_scans']} scans), confident outside 0.3 m / 10 deg:"
                f" {gl['runs_with_confident_outside_tolerance']} (largest error while confident"
                f" {gl['max_error_while_confident_m']} m /"
                f" {gl['max_heading_error_while_confident_deg']} deg);"
                f" confident at the end: {gl['runs_confident_at_end']}"
                f" ({gl['runs_converged_and_confident_at_end']} of them converged),"
                f" median {gl['median_scans_to_confident']} scans to the first confident one;"
                f" old covariance-only definition: {gl['runs_with_confident_wrong_covariance_only']}"
                " runs confident wrong"
            )
            print(
                f"{name}: symloc global: claimed in {gl['symloc_runs_claimed']}/{gl['starts']}"
                f" starts; confident wrong (> 1 m / 30 deg) in {gl['symloc_runs_confident_wrong']};"
                f" outside 0.1 m / 5 deg in {gl['symloc_runs_outside_tolerance']} starts"
                f" ({gl['symloc_outside_tolerance_scans']} scans, of which"
                f" {gl['symloc_outside_tolerance_reference_fits_worse']} where the reference"
                " fits the scan worse than the claim)"
            )
        results.append(entry)
        # a run of the eight logs takes about an hour: what is done survives a stop
        write_json(args.json, {"seed": args.seed, "logs": results, "complete": False})
        fig_logs.append(
            {"name": name, "grid": grid, "truth": truth, "estimate": est, "stamps": log.stamps}
        )
    from symloc.figures.mcl import amcl_carmen_figure

    fig = amcl_carmen_figure(fig_logs, args.out / "amcl_carmen.png")
    print(f"wrote {fig}")
    if global_traces:
        from symloc.figures.mcl import amcl_global_confidence_figure

        fig = amcl_global_confidence_figure(global_traces, args.out / "amcl_carmen_global.png")
        print(f"wrote {fig}")
    write_json(args.json, {"seed": args.seed, "logs": results, "complete": True})
    write_results_file(args, clock, config, {"logs": results})
    return 0
