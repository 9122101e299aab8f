"""Complete SLAM runs with their evaluation: a CARMEN log or a simulated exploration.

- :func:`run_carmen`: read a log, make odometry (:func:`carmen_odometry`: a named regime of
  :mod:`symloc.sim.odometry_noise` applied to the increments of the corrected poses, seeded,
  or the log's own odometry where it has real odometry), run SLAM, and compare with the
  corrected poses (ATE with SE(2) alignment, RPE over consecutive scans).
- :func:`run_simulated`: build a room, drive :func:`~symloc.bench.exploration.simulate_exploration`
  with exact wheel odometry, apply the regime to the increments of the true poses at the
  scans, run SLAM and compare with the ground truth (trajectory and rasterised map).
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import as_rng
from symloc.bench.slam_metrics import AteResult, MapAgreement, RpeResult, ate, map_agreement, rpe
from symloc.errors import ConfigurationError, DataFormatError
from symloc.geometry import compose
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.io.carmen import CarmenLog, read_carmen, stamps_usable
from symloc.sim.odometry_noise import ODOMETRY_REGIMES, OdometryRegime, regime_odometry
from symloc.slam.slam import SlamParams, SlamResult, run_slam

__all__ = [
    "ODOMETRY_CHOICES",
    "SIM_WORLDS",
    "SlamRun",
    "carmen_odometry",
    "log_duration",
    "log_name",
    "log_odometry",
    "map_build_odometry",
    "odometry_seed",
    "run_carmen",
    "run_simulated",
]

#: ``--odometry`` choices: the simulated regimes and the log's own odometry.
ODOMETRY_CHOICES = (*ODOMETRY_REGIMES, "log")

FloatArray = NDArray[np.float64]

#: Simulated worlds of ``symloc map build --world`` and the slam experiment:
#: name -> (room builder name, G-V distance [m], inside the lab).
SIM_WORLDS: dict[str, tuple[str, float, bool]] = {
    "square": ("square", 1.5 * math.sqrt(2.0), True),  # the paper's 3 m x 3 m room in a lab
    "l_shaped": ("l_shaped", 4.0, False),
    "hallway": ("hallway", 5.0, False),
}


@dataclass(frozen=True, eq=False)
class SlamRun:
    """A SLAM run and its evaluation.

    Attributes
    ----------
    name : str
    result : SlamResult
    reference : ndarray of shape (N, 3)
        Ground truth (simulation) or corrected poses (CARMEN).
    odometry : ndarray of shape (N, 3)
    duration : float or None
        Real (or simulated) duration of the data [s]; None when the log's stamps are not
        usable (:func:`log_duration`).
    ate, ate_odometry : AteResult
        Of the SLAM trajectory and of the raw odometry.
    rpe : RpeResult
    realtime_factor : float
        ``duration / total CPU time`` of the SLAM run (> 1: faster than real time); NaN
        without a duration.
    realtime_factor_wall : float
        ``duration / wall-clock time`` (depends on the load of the machine); NaN without a
        duration.
    map_agreement, map_agreement_tol1 : MapAgreement or None
        Against the rasterised ground truth (simulation only), exact and within one cell.
    truth_grid : OccupancyGrid or None
    config : dict
    """

    name: str
    result: SlamResult
    reference: FloatArray
    odometry: FloatArray
    duration: float | None
    ate: AteResult
    ate_odometry: AteResult
    rpe: RpeResult
    realtime_factor: float
    realtime_factor_wall: float
    map_agreement: MapAgreement | None = None
    map_agreement_tol1: MapAgreement | None = None
    truth_grid: OccupancyGrid | None = None
    config: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """Plain numbers for printing and JSON."""
        r = self.result
        out: dict[str, Any] = {
            "name": self.name,
            "scans": int(r.poses.shape[0]),
            "duration_s": self.duration,
            "ate_rmse_m": self.ate.rmse,
            "ate_max_m": self.ate.max,
            "ate_odometry_rmse_m": self.ate_odometry.rmse,
            "rpe_trans_rmse_m": self.rpe.trans_rmse,
            "rpe_rot_rmse_deg": math.degrees(self.rpe.rot_rmse),
            "loop_closures": len(r.loop_closures),
            "loops_rejected": len(r.rejected_loops),
            "doubtful": r.doubtful,
            "warnings": list(r.warnings),
            "loop_searches": r.n_loop_searches,
            "retries": r.n_retries,
            "submaps": r.n_submaps,
            "cpu_s": r.timings["total_cpu"],
            "wall_s": r.timings["total"],
            "realtime_factor_cpu": self.realtime_factor,
            "realtime_factor_wall": self.realtime_factor_wall,
            "timings_s": dict(r.timings),
        }
        if self.map_agreement is not None and self.map_agreement_tol1 is not None:
            out["map_agreement"] = self.map_agreement.fraction
            out["map_agreement_tol1"] = self.map_agreement_tol1.fraction
            out["map_occupied_agreement_tol1"] = self.map_agreement_tol1.occupied_fraction
            out["map_coverage"] = self.map_agreement.coverage
        return out


def _evaluate(
    name: str,
    result: SlamResult,
    reference: FloatArray,
    odometry: FloatArray,
    duration: float | None,
    **extra: Any,
) -> SlamRun:
    t = result.timings
    nan = float("nan")
    return SlamRun(
        name=name,
        result=result,
        reference=reference,
        odometry=odometry,
        duration=duration,
        ate=ate(reference, result.poses),
        ate_odometry=ate(reference, odometry),
        rpe=rpe(reference, result.poses),
        realtime_factor=nan if duration is None else duration / max(t["total_cpu"], 1e-9),
        realtime_factor_wall=nan if duration is None else duration / max(t["total"], 1e-9),
        **extra,
    )


def _regime(odometry: str | OdometryRegime) -> OdometryRegime | None:
    """The regime of an ``odometry`` choice (None for ``"log"``)."""
    if isinstance(odometry, OdometryRegime):
        return odometry
    if odometry == "log":
        return None
    if odometry not in ODOMETRY_REGIMES:
        raise ConfigurationError(
            f"odometry: expected one of {list(ODOMETRY_CHOICES)}, got {odometry!r}"
        )
    return ODOMETRY_REGIMES[odometry]


def log_odometry(log: CarmenLog, name: str = "log") -> FloatArray:
    """The log's own odometry of the laser ``(N, 3)``: FLASER odometry fields + mount offset.

    The odometry fields are the robot's odometry pose; the laser sits ``robot_frontlaser_offset``
    [m] ahead of it (PARAM, default 0).

    Raises
    ------
    ConfigurationError
        The odometry fields equal the laser poses (the "corrected" logs of the Radish repository
        wrote the corrected pose into both): the log carries no real odometry.
    """
    odom = log.odom_poses
    ref = log.laser_poses
    if odom.shape[0] == 0 or np.allclose(odom, ref, atol=1e-6):
        raise ConfigurationError(
            f"odometry 'log': {name} carries no real odometry (its FLASER odometry fields equal"
            " the corrected laser poses); use --odometry realistic or heavy"
        )
    try:
        offset = float(log.params.get("robot_frontlaser_offset", "0") or 0.0)
    except ValueError as err:
        raise ConfigurationError(
            f"{name}: PARAM robot_frontlaser_offset: expected a number [m]"
        ) from err
    return compose(odom, np.array([offset, 0.0, 0.0]))


def carmen_odometry(
    log: CarmenLog,
    odometry: str | OdometryRegime,
    rng: np.random.Generator | int | None,
    *,
    name: str = "log",
) -> FloatArray:
    """Odometry ``(N, 3)`` for every scan of ``log``: a regime on the corrected poses, or ``log``.

    Deterministic for a given seed; the same input for symloc and its peers.
    """
    regime = _regime(odometry)
    if regime is None:
        return log_odometry(log, name)
    return regime_odometry(log.laser_poses, regime, as_rng(rng))


def log_duration(stamps: FloatArray) -> float | None:
    """Duration [s] of a log from its scan stamps, None when they are not usable.

    Usable: at least 90 % of consecutive stamps increase (orebro's are all 0 and csail's are
    truncated to six significant digits, so neither gives a duration).
    """
    if not stamps_usable(stamps):
        return None
    return float(stamps[-1] - stamps[0])


def _truncated(log: CarmenLog, max_scans: int | None) -> CarmenLog:
    if max_scans is None:
        return log
    return CarmenLog(log.scans[:max_scans], log.odometry, log.params, log.skipped)


def log_name(path: str | Path) -> str:
    """``intel`` for ``.../intel-corrected.log.gz``."""
    return Path(path).name.split(".")[0].removesuffix("-corrected")


def odometry_seed(name: str, seed: int) -> np.random.SeedSequence:
    """The odometry noise stream of (log or world ``name``, ``seed``).

    ``symloc map build``, ``symloc experiment slam`` and ``symloc bench slam`` all draw from it,
    so one log, seed and regime give one noisy odometry, and so one ATE, whichever command runs
    it; and each log's stream is independent of the others'.
    """
    return np.random.SeedSequence([int(seed), zlib.crc32(name.encode())])


def _noise_rng(name: str, rng: np.random.Generator | int | None) -> np.random.Generator:
    """An int ``rng`` is a seed: :func:`odometry_seed` of it; anything else as given."""
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        return np.random.default_rng(odometry_seed(name, int(rng)))
    return as_rng(rng)


def map_build_odometry(
    log: CarmenLog, name: str, odometry: str | OdometryRegime, seed: int
) -> FloatArray:
    """The odometry ``(N, 3)`` that ``symloc map build --carmen LOG --odometry R --seed N`` (and
    :func:`run_carmen` with an int ``rng``) gives SLAM for log ``name``: :func:`carmen_odometry`
    drawn from :func:`odometry_seed` (``name``, ``seed``). ``symloc ros carmen-to-bag --odometry
    R --seed N`` writes it on ``/odom``, so ``symloc replay --build-map`` maps the bag from the
    same input as ``map build --carmen`` maps the log."""
    return carmen_odometry(log, odometry, _noise_rng(name, int(seed)), name=name)


def run_carmen(
    path: str | Path,
    *,
    odometry: str | OdometryRegime = "heavy",
    rng: np.random.Generator | int | None = 0,
    params: SlamParams | None = None,
    max_scans: int | None = None,
    progress: bool = True,
) -> SlamRun:
    """SLAM on a CARMEN log with odometry from :func:`carmen_odometry` (see module doc).

    An int ``rng`` is the run's seed: the odometry noise is drawn from
    :func:`odometry_seed` (log name, seed), as ``symloc bench slam`` draws it.
    """
    name = log_name(path)
    log = _truncated(read_carmen(path), max_scans)
    if len(log.scans) < 2:
        raise DataFormatError(
            f"{path}: {len(log.scans)} laser scan(s) (FLASER / ROBOTLASER1 lines); SLAM needs at "
            "least 2"
        )
    reference = log.laser_poses
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        odom = map_build_odometry(log, name, odometry, int(rng))
    else:
        odom = carmen_odometry(log, odometry, as_rng(rng), name=name)
    scans = [s.scan for s in log.scans]
    result = run_slam(scans, odom, params, progress=progress, desc=name)
    duration = log_duration(log.stamps)
    regime = _regime(odometry)
    return _evaluate(
        name,
        result,
        reference,
        odom,
        duration,
        config={
            "odometry": regime.describe() if regime is not None else "log",
            "log": str(path),
        },
    )


def run_simulated(
    world: str,
    *,
    odometry: str | OdometryRegime = "heavy",
    rng: np.random.Generator | int | None = 0,
    params: SlamParams | None = None,
    laps: float = 1.3,
    progress: bool = True,
) -> SlamRun:
    """SLAM on a simulated exploration of ``world`` (a key of :data:`SIM_WORLDS`).

    An int ``rng`` is the run's seed, drawn through :func:`odometry_seed` (world name, seed)
    as for a log: one world and seed drive and measure alike in every command.
    """
    if world not in SIM_WORLDS:
        raise ConfigurationError(f"world: expected one of {sorted(SIM_WORLDS)}, got {world!r}")
    regime = _regime(odometry)
    if regime is None:
        raise ConfigurationError("odometry: 'log' needs a log; a simulated world takes a regime")
    # imported here: the simulator (lidar, rooms, OpenCV, numba) is not needed on a log
    from symloc.bench.exploration import simulate_exploration
    from symloc.sim.rasterize import world_to_grid
    from symloc.sim.rooms import build_room

    room_name, gv, in_lab = SIM_WORLDS[world]
    room = build_room(room_name, gv, lab=in_lab)
    gen = _noise_rng(world, rng)
    run = simulate_exploration(room, alphas=(0.0, 0.0, 0.0, 0.0), laps=laps, rng=gen)
    odom = regime_odometry(run.truth, regime, gen)
    result = run_slam(run.scans, odom, params, progress=progress, desc=world)
    res = result.grid.resolution
    truth_grid = world_to_grid(room.world, res, free_seeds=run.truth[:1, :2])
    return _evaluate(
        world,
        result,
        run.truth,
        odom,
        run.duration,
        map_agreement=map_agreement(result.grid, truth_grid),
        map_agreement_tol1=map_agreement(result.grid, truth_grid, tolerance=1),
        truth_grid=truth_grid,
        config={
            "odometry": regime.describe(),
            "room": room_name,
            "gv": gv,
            "lab": in_lab,
            "laps": laps,
        },
    )
