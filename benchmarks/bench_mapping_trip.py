"""Benchmark: the accuracy of the bench's SLAM maps (the mapping trips of ``bench localization``).

For each (family, dev world seed) the world is built and mapped exactly as
``symloc bench localization --regime realistic`` maps it
(:func:`symloc.bench.localization.run_world`: :func:`symloc.bench.scenario.build_scenario`
with ``rng`` = ``WorldRef.robot_seed``, ``map_source="slam"``, one exploration lap, the ``realistic``
sensors; keyframes, which the ``decide`` method records, draw from a stream of their own and do
not change the map, so they are off unless ``--keyframes``). Printed per world:

- the mapping trip's SLAM pose error in the map frame after the rigid (Umeyama) fit to the
  truth, as the bench records it (:attr:`Scenario.slam_error_p95`): p95, mean and max [cm];
- the **wall error** of the map, the error the localizer inherits: every occupied cell of the
  SLAM grid, moved into the world frame by the same fit, and its distance to the true walls
  (:meth:`symloc.sim.world.World.distance` at the lidar's height): p95, p99 and max [cm].
  A 5 cm cell's centre is up to 3.5 cm from the wall it contains, so the same figures for the
  ground-truth raster of the world (:func:`symloc.sim.rasterize.world_to_grid`) are printed as
  the floor (``raster p95/max``);
- loop closures accepted, and the seconds SLAM took (wall and CPU);
- **the map's own error as SLAM estimates it** (:mod:`symloc.slam.map_error`: its node scans
  aligned again to the finished map), std and p95 [cm], beside the truth it should cover: at the
  end, how many worlds' shape p95 (the map's distortion, scale removed) lies within the 95 %
  radius (2.45 std) of the error the claim gate then assumes (the larger of the estimate and
  its 1 cm default, ``ClaimConfig.map_std_xy``); and place by place, the share of the trip's
  scans whose distortion lies inside the 95 % ellipse of SLAM's map error field there
  (``field cov``: the field alone; ``gate``: its eigenvalues raised to that assumed std, as the
  claim gate reads it).

Per family the worst world is printed at the end. Each world's row is appended to
``<out>/bench_mapping_trip.partial.jsonl`` as soon as it is done.

``--save-trips DIR`` also stores each trip (scans, odometry, true positions) as a pickle, and
``--replay DIR`` re-runs only SLAM on stored trips (seconds instead of minutes per world: the
simulation is most of the cost), with the same figures, to compare SLAM changes on the very
same data.

Run: ``python benchmarks/bench_mapping_trip.py [--families l_shape ...] [--seeds 0 1]
[--out DIR] [--save-trips DIR | --replay DIR]``
"""

from __future__ import annotations

import argparse
import json
import math
import pickle
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

import symloc.bench.scenario as scenario_module
from symloc.bench.scenario import build_scenario
from symloc.bench.slam_metrics import field_coverage, similarity_residuals, umeyama_se2
from symloc.bench.world_sources import WorldRef, build_world
from symloc.geometry import compose, inverse
from symloc.localizer.claim import ClaimConfig
from symloc.sim.generator import FAMILIES
from symloc.sim.lidar import LIDAR_MOUNT_HEIGHT
from symloc.sim.rasterize import world_to_grid
from symloc.slam import run_slam


def wall_error(grid: Any, world: Any, map_from_world: np.ndarray) -> dict[str, float]:
    """Distances [m] from the occupied cells of ``grid`` (map frame) to the walls of ``world``.

    The cells' centres (K, 2) are moved into the world frame with ``inverse(map_from_world)``
    and measured against the primitives taller than the lidar plane.
    """
    rc = np.argwhere(grid.occupied_mask)
    if rc.size == 0:
        return {"p95": math.nan, "p99": math.nan, "max": math.nan, "cells": 0}
    xy_map = grid.cell_to_world(rc)
    pts = np.c_[xy_map, np.zeros(len(xy_map))]
    xy = np.asarray(compose(inverse(map_from_world), pts))[:, :2]
    d = np.concatenate(
        [
            world.distance(xy[k : k + 2000], min_height=LIDAR_MOUNT_HEIGHT)
            for k in range(0, len(xy), 2000)
        ]
    )
    return {
        "p95": float(np.percentile(d, 95)),
        "p99": float(np.percentile(d, 99)),
        "max": float(d.max()),
        "cells": int(d.size),
    }


def face_error(
    grid: Any, world: Any, map_from_world: np.ndarray, *, seen_within: float = 0.5
) -> dict[str, float]:
    """Distances [m] from the true walls to the nearest occupied cell of ``grid``.

    What the localizer's likelihood field inherits: the true walls taller than the lidar plane
    are sampled every 2 cm, moved into the map frame by ``map_from_world``, and each sample's
    distance to the nearest occupied cell centre is taken. Samples farther than
    ``seen_within`` [m] from every occupied cell count as walls the trip never saw (the lab
    behind the room) and are left out. A wall the map draws 10 cm too far out (or eroded on
    its inner face) shows here; occupied cells behind a wall, which the field never reaches,
    do not.
    """
    rc = np.argwhere(grid.occupied_mask)
    tall = np.asarray(world.wall_heights) > LIDAR_MOUNT_HEIGHT
    samples = []
    for x0, y0, x1, y1 in np.asarray(world.walls)[tall]:
        n = max(int(math.hypot(x1 - x0, y1 - y0) / 0.02), 1)
        t = (np.arange(n) + 0.5) / n
        samples.append(np.c_[x0 + t * (x1 - x0), y0 + t * (y1 - y0)])
    ctall = np.asarray(world.circle_heights) > LIDAR_MOUNT_HEIGHT
    for cx, cy, r in np.asarray(world.circles)[ctall]:
        n = max(int(2 * math.pi * r / 0.02), 8)
        a = 2 * math.pi * (np.arange(n) + 0.5) / n
        samples.append(np.c_[cx + r * np.cos(a), cy + r * np.sin(a)])
    if rc.size == 0 or not samples:
        return {"p95": math.nan, "p99": math.nan, "max": math.nan, "samples": 0}
    pts = np.concatenate(samples)
    xy = np.asarray(compose(map_from_world, np.c_[pts, np.zeros(len(pts))]))[:, :2]
    d, _ = cKDTree(grid.cell_to_world(rc)).query(xy)
    d = d[d <= seen_within]
    if d.size == 0:
        return {"p95": math.nan, "p99": math.nan, "max": math.nan, "samples": 0}
    return {
        "p95": float(np.percentile(d, 95)),
        "p99": float(np.percentile(d, 99)),
        "max": float(d.max()),
        "samples": int(d.size),
    }


class _TripRecorder:
    """Wraps the scenario module's ``run_slam`` and ``umeyama_se2`` to keep the trip's data."""

    def __init__(self) -> None:
        self.scans: list[Any] = []
        self.odoms = np.zeros((0, 3))
        self.truth_xy = np.zeros((0, 2))
        self.truth = np.zeros((0, 3))
        self.result: Any = None

    def __enter__(self) -> _TripRecorder:
        self._run_slam = scenario_module.run_slam
        self._umeyama = scenario_module.umeyama_se2

        def rec_slam(scans: Any, odoms: Any, **kw: Any) -> Any:
            self.scans = list(scans)
            self.odoms = np.array(odoms)
            self.result = self._run_slam(scans, odoms, **kw)
            return self.result

        def rec_umeyama(source: Any, target: Any) -> Any:
            self.truth_xy = np.array(source)
            # the scenario passes a view of the true poses (N, 3): keep the headings too
            base = getattr(source, "base", None)
            if isinstance(base, np.ndarray) and base.shape == (len(source), 3):
                self.truth = np.array(base)
            return self._umeyama(source, target)

        scenario_module.run_slam = rec_slam  # type: ignore[assignment]
        scenario_module.umeyama_se2 = rec_umeyama  # type: ignore[assignment]
        return self

    def __exit__(self, *exc: object) -> None:
        scenario_module.run_slam = self._run_slam  # type: ignore[assignment]
        scenario_module.umeyama_se2 = self._umeyama  # type: ignore[assignment]


def _ref(family: str, seed: int) -> WorldRef:
    return WorldRef("generated" if family in FAMILIES else "builtin", family, seed)


def _room(family: str, seed: int) -> Any:
    return build_world(_ref(family, seed))


def _pose_errors(slam_poses: np.ndarray, truth_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-scan position errors (N,) [m] after the rigid fit, and the fit ``map_from_world``."""
    m_from_w = umeyama_se2(truth_xy, slam_poses[:, :2])
    t = np.c_[truth_xy, np.zeros(len(truth_xy))]
    in_map = np.asarray(compose(m_from_w, t))
    return np.hypot(*(slam_poses[:, :2] - in_map[:, :2]).T), m_from_w


#: The claim gate's own map error [m] (``ClaimConfig.map_std_xy``), which a declared estimate
#: only raises: the floor of every place's covariance where the gate reads the field.
_GATE = ClaimConfig()
GATE_MAP_STD = _GATE.map_std_xy


def _coverage_of(field: Any, xy: np.ndarray, residuals: np.ndarray, floor: float) -> float:
    """:func:`symloc.bench.slam_metrics.field_coverage`; NaN without a field."""
    return math.nan if field is None else field_coverage(field, xy, residuals, floor)


def _row(
    family: str,
    seed: int,
    slam: Any,
    truth_xy: np.ndarray,
    room: Any,
    seconds: float,
) -> dict[str, Any]:
    poses = np.asarray(slam.poses)
    err, m_from_w = _pose_errors(poses, truth_xy)
    residuals, sim_scale = similarity_residuals(truth_xy, poses[:, :2])
    sim_err = np.hypot(*residuals.T)
    field = slam.map_error_field
    walls = wall_error(slam.grid, room.world, m_from_w)
    raster = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    floor = wall_error(raster, room.world, np.zeros(3))
    faces = face_error(slam.grid, room.world, m_from_w)
    faces_floor = face_error(raster, room.world, np.zeros(3))
    s = slam.summary()
    return {
        "world": f"{family}#{seed}",
        "family": family,
        "seed": seed,
        "scans": len(truth_xy),
        "pose_p95": float(np.percentile(err, 95)),
        "pose_mean": float(err.mean()),
        "pose_max": float(err.max()),
        "shape_p95": float(np.percentile(sim_err, 95)),
        "map_scale": sim_scale,
        "wall_p95": walls["p95"],
        "wall_p99": walls["p99"],
        "wall_max": walls["max"],
        "raster_p95": floor["p95"],
        "raster_max": floor["max"],
        "face_p95": faces["p95"],
        "face_p99": faces["p99"],
        "face_max": faces["max"],
        "raster_face_p95": faces_floor["p95"],
        "raster_face_max": faces_floor["max"],
        "loops": int(s["loops_accepted"]),
        "loops_rejected": int(s["loops_rejected"]),
        "slam_s": seconds,
        "slam_cpu_s": float(s["slam_cpu_s"]),
        "warnings": list(slam.warnings),
        "est_std": math.nan if slam.map_error is None else float(slam.map_error.std_xy),
        "est_p95": math.nan if slam.map_error is None else float(slam.map_error.p95_xy),
        # the map's error as SLAM estimates it place by place, against the map's distortion
        "field_coverage": _coverage_of(field, poses[:, :2], residuals, 0.0),
        "field_coverage_gate": _coverage_of(
            field,
            poses[:, :2],
            residuals,
            _GATE.with_map_error(
                None if slam.map_error is None else slam.map_error.std_xy
            ).map_std_xy,
        ),
        "field_major_std_median": (
            math.nan if field is None else float(np.median(field.major_std))
        ),
    }


def map_world(
    family: str, seed: int, args: argparse.Namespace
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Build and map one world as the localization bench does; its row and its trip."""
    room = _room(family, seed)
    with tempfile.TemporaryDirectory(prefix="bench-mapping-") as tmp, _TripRecorder() as rec:
        scen = build_scenario(
            room,
            rng=_ref(family, seed).robot_seed,
            workdir=Path(tmp),
            map_source="slam",
            explore_laps=args.explore_laps,
            regime=args.regime,
            keyframes=True if args.keyframes else None,
        )
        scen.close()
    row = _row(family, seed, rec.result, rec.truth_xy, room, scen.slam_seconds)
    # the bench's own figure, for the record (must equal pose_p95)
    row["scenario_slam_error_p95"] = scen.slam_error_p95
    assert scen.hardware is not None
    row["lidar_scale"] = scen.hardware.lidar_scale
    row["lidar_offset"] = scen.hardware.lidar_offset
    trip = {
        "scans": rec.scans,
        "odoms": rec.odoms,
        "truth_xy": rec.truth_xy,
        "truth": rec.truth,
        "lidar_scale": scen.hardware.lidar_scale,
        "lidar_offset": scen.hardware.lidar_offset,
    }
    return row, trip


def replay_world(family: str, seed: int, trip: dict[str, Any]) -> dict[str, Any]:
    """Re-run SLAM only on a stored trip."""
    room = _room(family, seed)
    t0 = time.perf_counter()
    slam = run_slam(trip["scans"], trip["odoms"], progress=False)
    seconds = time.perf_counter() - t0
    row = _row(family, seed, slam, trip["truth_xy"], room, seconds)
    row["lidar_scale"] = trip.get("lidar_scale", math.nan)
    row["lidar_offset"] = trip.get("lidar_offset", math.nan)
    return row


HEADER = (
    f"{'world':<18}{'scans':>6}  {'pose p95/mean/max [cm]':>23}  {'shape p95':>9}"
    f"  {'face p95/p99/max [cm]':>22}"
    f"  {'cells p95/p99/max [cm]':>22}  {'raster face/cells p95':>21}  {'loops':>5}"
    f"  {'slam s':>6}  {'cpu s':>6}  {'lidar/map scale':>15}  {'est std/p95':>11}"
    f"  {'field cov/gate':>14}"
)


def _fmt(r: dict[str, Any]) -> str:
    return (
        f"{r['world']:<18}{r['scans']:>6}  "
        f"{100 * r['pose_p95']:>7.1f}{100 * r['pose_mean']:>7.1f}{100 * r['pose_max']:>9.1f}  "
        f"{100 * r['shape_p95']:>9.1f}  "
        f"{100 * r['face_p95']:>6.1f}{100 * r['face_p99']:>7.1f}{100 * r['face_max']:>9.1f}  "
        f"{100 * r['wall_p95']:>6.1f}{100 * r['wall_p99']:>7.1f}{100 * r['wall_max']:>9.1f}  "
        f"{100 * r['raster_face_p95']:>10.1f}{100 * r['raster_p95']:>11.1f}  {r['loops']:>5}  "
        f"{r['slam_s']:>6.1f}  {r['slam_cpu_s']:>6.1f}  {100 * r['lidar_scale']:>+7.2f}/{100 * (r['map_scale'] - 1):+.2f}%"
        f"  {100 * r.get('est_std', math.nan):>5.1f}/{100 * r.get('est_p95', math.nan):<5.1f}"
        f"  {r.get('field_coverage', math.nan):>7.2f}/{r.get('field_coverage_gate', math.nan):<5.2f}"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--families", nargs="+", default=list(FAMILIES), help="generator families (default all)"
    )
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1], help="dev world seeds")
    parser.add_argument("--regime", default="realistic", help="sensor regime (realistic)")
    parser.add_argument("--explore-laps", type=float, default=1.0, help="as the bench (1)")
    parser.add_argument(
        "--keyframes", action="store_true", help="record keyframes too (the map is the same)"
    )
    parser.add_argument("--out", type=Path, default=Path("bench_mapping_trip_out"))
    parser.add_argument("--save-trips", type=Path, default=None, help="store each trip here")
    parser.add_argument("--replay", type=Path, default=None, help="re-run SLAM on stored trips")
    parser.add_argument(
        "--results", type=Path, default=None, help="write a results file (docs/results format)"
    )
    args = parser.parse_args()
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    worlds = [(f, s) for f in args.families for s in args.seeds]
    print("# bench_mapping_trip")
    print(f"#   families: {' '.join(args.families)}")
    print(f"#   world seeds (build_scenario rng = WorldRef.robot_seed): {args.seeds}")
    if args.replay is not None:
        print(f"#   replay: SLAM only, on the trips stored in {args.replay}")
    else:
        print(
            f"#   as bench localization: map_source slam, explore_laps {args.explore_laps:g}, "
            f"regime {args.regime}, keyframes {'on' if args.keyframes else 'off'}"
        )
    args.out.mkdir(parents=True, exist_ok=True)
    partial = args.out / "bench_mapping_trip.partial.jsonl"
    partial.write_text("")
    if args.save_trips is not None:
        args.save_trips.mkdir(parents=True, exist_ok=True)
    print(HEADER, flush=True)
    rows: list[dict[str, Any]] = []
    for n, (family, seed) in enumerate(worlds, 1):
        print(f"# [{n}/{len(worlds)}] {family}#{seed} ...", file=sys.stderr, flush=True)
        if args.replay is not None:
            path = args.replay / f"{family}_{seed}.pkl"
            if not path.is_file():
                print(f"# {family}#{seed}: no stored trip {path}", flush=True)
                continue
            with path.open("rb") as fh:
                row = replay_world(family, seed, pickle.load(fh))
        else:
            row, trip = map_world(family, seed, args)
            if args.save_trips is not None:
                with (args.save_trips / f"{family}_{seed}.pkl").open("wb") as fh:
                    pickle.dump(trip, fh)
        rows.append(row)
        with partial.open("a") as fh:
            fh.write(json.dumps(row) + "\n")
        print(_fmt(row), flush=True)
    print("\n# worst world per family (by pose p95)")
    print(HEADER)
    for family in args.families:
        fam = [r for r in rows if r["family"] == family]
        if fam:
            print(_fmt(max(fam, key=lambda r: r["pose_p95"])))
    if rows:
        p95 = np.array([r["pose_p95"] for r in rows])
        print(
            f"# {len(rows)} worlds: pose p95 median {100 * np.median(p95):.1f} cm, worst "
            f"{100 * p95.max():.1f} cm; {int(np.sum(p95 <= 0.02))} at most 2 cm; SLAM seconds "
            f"total {sum(r['slam_s'] for r in rows):.0f}"
        )
        _coverage(rows)
        families = per_family(rows)
        print(
            "\n# per family (worst world): pose p95 [cm] (rigid fit), shape p95 [cm] (scale fitted),"
            " |lidar scale| [%], field coverage (min over worlds)"
        )
        for fam in families:
            print(
                f"{fam['family']:<18}{fam['worlds']:>3}  {100 * fam['pose_p95']:>6.1f}"
                f"  {100 * fam['shape_p95']:>6.1f}  {100 * fam['lidar_scale_abs']:>6.2f}"
                f"  {fam['field_coverage_min']:>6.2f}"
            )
        if args.results is not None:
            from symloc.bench.results_file import write_bench_results

            written = write_bench_results(
                args.results,
                clock=clock,
                settings={
                    "families": args.families,
                    "seeds": args.seeds,
                    "regime": args.regime,
                    "explore_laps": args.explore_laps,
                    "keyframes": bool(args.keyframes),
                    "replay": None if args.replay is None else str(args.replay),
                    "gate_map_std_m": GATE_MAP_STD,
                },
                figures={"rows": rows, "families": families},
            )
            print(f"# results file: {written}")
    return 0


def per_family(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per family, in the order met: the number of worlds and the worst of each figure (pose
    and shape p95 [m], the lidar's absolute range scale error, the lowest field coverage)."""
    out: list[dict[str, Any]] = []
    for family in dict.fromkeys(r["family"] for r in rows):
        fam = [r for r in rows if r["family"] == family]
        out.append(
            {
                "family": family,
                "worlds": len(fam),
                "pose_p95": max(r["pose_p95"] for r in fam),
                "shape_p95": max(r["shape_p95"] for r in fam),
                "lidar_scale_abs": max(abs(r["lidar_scale"]) for r in fam),
                "field_coverage_min": float(np.nanmin([r["field_coverage"] for r in fam]))
                if any(math.isfinite(r["field_coverage"]) for r in fam)
                else math.nan,
            }
        )
    return out


def _coverage(rows: list[dict[str, Any]], default_std: float = GATE_MAP_STD) -> None:
    """How often the error the claim gate assumes covers the map's distortion (shape p95)."""
    est = np.array([r.get("est_std", math.nan) for r in rows])
    shape = np.array([r["shape_p95"] for r in rows])
    assumed = np.fmax(est, default_std)  # NaN estimate: the default
    covered = shape <= 2.45 * assumed
    print(
        f"# map error: estimated std median {100 * np.nanmedian(est):.1f} cm, max"
        f" {100 * np.nanmax(est):.1f} cm; shape p95 within 2.45 x the assumed std (larger of the"
        f" estimate and {100 * default_std:.0f} cm) in {int(covered.sum())} of {len(rows)} worlds"
        f" (with the {100 * default_std:.0f} cm default alone:"
        f" {int(np.sum(shape <= 2.45 * default_std))}); Spearman rank correlation of the"
        f" estimate with shape p95 {_spearman(est, shape):.2f}"
    )
    for r, ok in zip(rows, covered, strict=True):
        if not ok:
            print(
                f"#   not covered: {r['world']} shape p95 {100 * r['shape_p95']:.1f} cm,"
                f" estimated std {100 * r.get('est_std', math.nan):.1f} cm"
            )


def _spearman(a: np.ndarray, b: np.ndarray) -> float:
    ok = np.isfinite(a) & np.isfinite(b)
    if ok.sum() < 3:
        return math.nan
    ra = np.argsort(np.argsort(a[ok]))
    rb = np.argsort(np.argsort(b[ok]))
    return float(np.corrcoef(ra, rb)[0, 1])


if __name__ == "__main__":
    sys.exit(main())
