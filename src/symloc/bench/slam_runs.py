"""Complete SLAM runs with their evaluation: a CARMEN log or a simulated exploration.

- :func:`run_carmen`: read a log, make odometry by adding noise to the increments of the
  corrected poses (:func:`~symloc.sim.odometry_noise.noisy_odometry`, seeded), run SLAM,
  and compare with the corrected poses (ATE with SE(2) alignment, RPE over consecutive scans).
- :func:`run_simulated`: build a room, drive :func:`~symloc.bench.exploration.simulate_exploration`,
  run SLAM and compare with the ground truth (trajectory and rasterised map).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import as_rng
from symloc.bench.exploration import simulate_exploration
from symloc.bench.slam_metrics import AteResult, MapAgreement, RpeResult, ate, map_agreement, rpe
from symloc.errors import ConfigurationError
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.io.carmen import read_carmen
from symloc.sim.odometry_noise import DEFAULT_ALPHAS, noisy_odometry
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import build_room
from symloc.slam.slam import SlamParams, SlamResult, run_slam

__all__ = ["SIM_WORLDS", "SlamRun", "run_carmen", "run_simulated"]

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
    duration : float
        Real (or simulated) duration of the data [s].
    ate, ate_odometry : AteResult
        Of the SLAM trajectory and of the raw odometry.
    rpe : RpeResult
    realtime_factor : float
        ``duration / total CPU time`` of the SLAM run (> 1: faster than real time).
    realtime_factor_wall : float
        ``duration / wall-clock time`` (depends on the load of the machine).
    map_agreement, map_agreement_tol1 : MapAgreement or None
        Against the rasterised ground truth (simulation only), exact and within one cell.
    truth_grid : OccupancyGrid or None
    config : dict
    """

    name: str
    result: SlamResult
    reference: FloatArray
    odometry: FloatArray
    duration: float
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
    duration: float,
    **extra: Any,
) -> SlamRun:
    t = result.timings
    return SlamRun(
        name=name,
        result=result,
        reference=reference,
        odometry=odometry,
        duration=duration,
        ate=ate(reference, result.poses),
        ate_odometry=ate(reference, odometry),
        rpe=rpe(reference, result.poses),
        realtime_factor=duration / max(t["total_cpu"], 1e-9),
        realtime_factor_wall=duration / max(t["total"], 1e-9),
        **extra,
    )


def run_carmen(
    path: str | Path,
    *,
    alphas: tuple[float, float, float, float] = DEFAULT_ALPHAS,
    rng: np.random.Generator | int | None = 0,
    params: SlamParams | None = None,
    max_scans: int | None = None,
    progress: bool = True,
) -> SlamRun:
    """SLAM on a CARMEN log with odometry made from its corrected poses (see module doc)."""

    log = read_carmen(path)
    scans_all = log.scans if max_scans is None else log.scans[:max_scans]
    reference = np.array([s.laser_pose for s in scans_all])
    scans = [s.scan for s in scans_all]
    odom = noisy_odometry(reference, alphas, as_rng(rng))
    name = Path(path).name.split(".")[0]
    result = run_slam(scans, odom, params, progress=progress, desc=name)
    duration = float(scans_all[-1].stamp - scans_all[0].stamp)
    return _evaluate(
        name, result, reference, odom, duration, config={"alphas": alphas, "log": str(path)}
    )


def run_simulated(
    world: str,
    *,
    alphas: tuple[float, float, float, float] = DEFAULT_ALPHAS,
    rng: np.random.Generator | int | None = 0,
    params: SlamParams | None = None,
    laps: float = 1.3,
    progress: bool = True,
) -> SlamRun:
    """SLAM on a simulated exploration of ``world`` (a key of :data:`SIM_WORLDS`)."""

    if world not in SIM_WORLDS:
        raise ConfigurationError(f"world: expected one of {sorted(SIM_WORLDS)}, got {world!r}")
    room_name, gv, in_lab = SIM_WORLDS[world]
    room = build_room(room_name, gv, lab=in_lab)
    gen = as_rng(rng)
    run = simulate_exploration(room, alphas=alphas, laps=laps, rng=gen)
    result = run_slam(run.scans, run.odometry, params, progress=progress, desc=world)
    res = result.grid.resolution
    truth_grid = world_to_grid(room.world, res, free_seeds=run.truth[:1, :2])
    return _evaluate(
        world,
        result,
        run.truth,
        run.odometry,
        run.duration,
        map_agreement=map_agreement(result.grid, truth_grid),
        map_agreement_tol1=map_agreement(result.grid, truth_grid, tolerance=1),
        truth_grid=truth_grid,
        config={"alphas": alphas, "room": room_name, "gv": gv, "lab": in_lab, "laps": laps},
    )
