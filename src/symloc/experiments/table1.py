"""``symloc experiment table1``: the paper's Table 1 (Section 5.1) in the simulator, and more.

Protocol (the paper's): equilateral triangle, square, regular pentagon, regular hexagon and
round rooms with G-V distances 3, 5 and 7 m; a 15 m scanner (the paper's Gazebo sensor,
``PAPER_15M``: 360 beams, sigma 10 mm); the robot at ``--positions`` (50) positions spread
evenly inside each room (``Room.positions_inside``, 0.3 m from the walls) with a random
heading; one scan per position. A recognition is correct when the judgement names the right
symmetry: the room's kind and its order (n for the n-gon, infinite for the circle). Counted
for both centroids of the judgement (``mean``: the paper's eq. 3-4; ``area``: the scan
polygon's) and for the paper's Algorithm 1 as written.

Rows the paper does not have: the same for the LDS-01 (3.5 m range: rooms larger than that
are not seen whole, so the judgement answers "unknown", a sensor limit) and RPLIDAR A2
presets; and false positives on asymmetric rooms (rectangles, rhombi, kites, L-shaped rooms,
squares with furniture, squares with an open door). A false positive claims more symmetry than
the room has: an order above the room's true order (a rectangle, order 2, judged a square,
order 4), or any symmetry for a room of order 1.

Every tolerance is derived from the preset's data-sheet noise (``SymmetryConfig.from_lidar``);
nothing is tuned to the test positions.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from symloc._checks import as_rng
from symloc.cli import options
from symloc.errors import ConfigurationError, WorldError
from symloc.experiments._common import (
    add_common_arguments,
    print_config,
    write_json,
    write_results_file,
)
from symloc.geometry import transform_points
from symloc.symmetry.order import SymmetryOrder

__all__ = ["FP_ROOMS", "SENSORS", "SHAPES", "register", "run_false_positives", "run_table1"]

SHAPES = ("triangle", "square", "pentagon", "hexagon", "circle")
GV_DISTANCES = (3.0, 5.0, 7.0)
SENSORS = ("paper_15m", "lds01", "rplidar_a2")
CENTROIDS = ("mean", "area")
PAPER_TABLE1 = {
    "triangle": (50, 50, 48),
    "square": (50, 50, 50),
    "pentagon": (50, 50, 50),
    "hexagon": (50, 50, 49),
    "circle": (50, 50, 50),
}
_SIDES = {"triangle": 3, "square": 4, "pentagon": 5, "hexagon": 6}


@dataclass(frozen=True)
class FPRoom:
    """An asymmetric (or less symmetric) test room: builder name, parameters, true order."""

    label: str
    family: str
    true_order: int


#: The false-positive set: (label, family, true rotational order).
FP_ROOMS = (
    FPRoom("rectangle 1.05:1", "rectangle", 2),
    FPRoom("rectangle 1.1:1", "rectangle", 2),
    FPRoom("rectangle 1.25:1", "rectangle", 2),
    FPRoom("rectangle 1.5:1", "rectangle", 2),
    FPRoom("rhombus 85 deg", "rhombus", 2),
    FPRoom("rhombus 75 deg", "rhombus", 2),
    FPRoom("rhombus 60 deg", "rhombus", 2),
    FPRoom("kite 0.8", "kite", 1),
    FPRoom("kite 0.6", "kite", 1),
    FPRoom("L-shaped 0.5", "l_shaped", 1),
    FPRoom("L-shaped 0.65", "l_shaped", 1),
    FPRoom("square + 1 box", "furniture", 1),
    FPRoom("square + 2 boxes + table", "furniture", 1),
    FPRoom("pentagon + 1 box", "furniture", 1),
    FPRoom("square + door", "door", 1),
    FPRoom("hexagon + door", "door", 1),
    FPRoom("circle + door", "door", 1),
)


def _build_fp_room(spec: FPRoom, gv: float, rng: np.random.Generator) -> Any:
    """Build one false-positive room (a ``symloc.sim.rooms.Room``)."""
    from symloc.sim import rooms
    from symloc.sim.world import World, polygon_walls

    label = spec.label
    if spec.family == "rectangle":
        aspect = float(label.split()[1].split(":")[0])
        d = 2 * gv / math.hypot(aspect, 1.0)
        return rooms.rectangle_room(aspect * d, d)
    if spec.family in ("rhombus", "kite"):
        if spec.family == "rhombus":
            alpha = math.radians(float(label.split()[1]))
            s = gv * 1.4
            v = np.array(
                [
                    [0.0, 0.0],
                    [s, 0.0],
                    [s + s * math.cos(alpha), s * math.sin(alpha)],
                    [s * math.cos(alpha), s * math.sin(alpha)],
                ]
            )
        else:
            ratio = float(label.split()[1])
            v = np.array([[0.0, -gv], [0.75 * gv, 0.0], [0.0, ratio * gv], [-0.75 * gv, 0.0]])
        v = v - v.mean(axis=0)
        walls = polygon_walls(v, name=spec.family)
        world = World(walls, rooms.WALL_HEIGHT)
        room = rooms.with_truth(
            rooms.Room(
                name=spec.family,
                kind=spec.family,
                world=world,
                boundary=v,
                corners=v.copy(),
                center=np.zeros(2),
                gv_distance=float(np.max(np.hypot(*v.T))),
                shape_order=spec.true_order,
                order=spec.true_order,
                regular=False,
                room_world=world,
            )
        )
        if room.order != spec.true_order:
            raise WorldError(
                f"FPRoom {label!r}: the geometry has order {room.order}, not {spec.true_order}"
            )
        return room
    if spec.family == "l_shaped":
        arm = float(label.split()[1])
        unit = rooms.l_shaped_room(1.0, arm=arm)
        return rooms.l_shaped_room(gv / unit.gv_distance, arm=arm)
    if spec.family == "furniture":
        base = label.split()[0]
        boxes = 2 if "2 boxes" in label else 1
        tables = 1 if "table" in label else 0
        return rooms.build_room(
            base, gv, lab=False, furniture=boxes, tables=tables, rng=int(rng.integers(2**31))
        )
    if spec.family == "door":
        return rooms.build_room(label.split()[0], gv, lab=False, door=True)
    raise ConfigurationError(
        f"FPRoom.family: expected rectangle, rhombus, kite, l_shaped, furniture or door,"
        f" got {spec.family!r}"
    )


def _expected(shape: str) -> tuple[str, SymmetryOrder]:
    if shape == "circle":
        return "circle", SymmetryOrder.CIRCLE
    return "polygon", SymmetryOrder.finite(_SIDES[shape])


def _center_error(report: Any, pose: np.ndarray, true_center: np.ndarray) -> float:
    world_c = transform_points(pose, report.center[None, :])[0]
    return float(np.hypot(*(world_c - true_center)))


def run_table1(
    *,
    seed: int = 0,
    positions: int = 50,
    sensors: tuple[str, ...] = SENSORS,
    shapes: tuple[str, ...] = SHAPES,
    gv_distances: tuple[float, ...] = GV_DISTANCES,
    progress: bool = True,
) -> dict[str, Any]:
    """Run the Table 1 protocol; returns the cells and the per-position outcomes.

    Returns
    -------
    dict
        ``cells``: one entry per (shape, gv, sensor, method, centroid) with ``correct``,
        ``trials``, ``unknown`` (verdicts "unknown"), centre errors [m] of the correct ones;
        ``positions``: per (shape, gv, sensor) the positions and correct flags (figure input).
    """
    from symloc.sim.lidar import PRESETS, simulate_scan
    from symloc.sim.rooms import build_room
    from symloc.symmetry import SymmetryConfig, algorithm1, judge_symmetry

    rng = as_rng(seed)
    cells: list[dict[str, Any]] = []
    per_position: list[dict[str, Any]] = []
    total = len(sensors) * len(shapes) * len(gv_distances) * positions
    bar = tqdm(total=total, desc="table1", file=sys.stderr, disable=not progress)
    timings: list[float] = []
    for sensor in sensors:
        preset = PRESETS[sensor]
        cfg = SymmetryConfig.from_lidar(preset)
        for shape in shapes:
            kind, order = _expected(shape)
            for gv in gv_distances:
                room = build_room(shape, gv, lab=False)
                pos = room.positions_inside(positions, margin=0.3)
                heads = rng.uniform(-math.pi, math.pi, size=pos.shape[0])
                poses = np.column_stack([pos, heads])
                outcome: dict[str, list[Any]] = {}
                errors: dict[str, list[float]] = {}
                unknown: dict[str, int] = {}
                for pose in poses:
                    scan = simulate_scan(room.world, pose, preset, rng)
                    for cen in CENTROIDS:
                        t0 = time.perf_counter()
                        rep = judge_symmetry(scan, config=cfg, centroid=cen)
                        timings.append(time.perf_counter() - t0)
                        ok = rep.symmetric and rep.kind == kind and rep.order == order
                        key = f"judge/{cen}"
                        outcome.setdefault(key, []).append(bool(ok))
                        unknown[key] = unknown.get(key, 0) + (rep.kind == "unknown")
                        if ok:
                            errors.setdefault(key, []).append(_center_error(rep, pose, room.center))
                        n_vertices = 4 if shape == "circle" else _SIDES[shape]
                        a1 = algorithm1(scan, n=n_vertices, config=cfg, centroid=cen)
                        want = "circle" if shape == "circle" else "polygon"
                        key = f"algorithm1/{cen}"
                        outcome.setdefault(key, []).append(bool(a1.symmetric and a1.kind == want))
                        unknown[key] = unknown.get(key, 0) + (a1.kind == "unknown")
                    bar.update(1)
                for key, flags in outcome.items():
                    method, cen = key.split("/")
                    errs = errors.get(key, [])
                    cells.append(
                        {
                            "shape": shape,
                            "gv": gv,
                            "sensor": sensor,
                            "method": method,
                            "centroid": cen,
                            "correct": int(sum(flags)),
                            "trials": len(flags),
                            "unknown": int(unknown.get(key, 0)),
                            "center_error_median": float(np.median(errs)) if errs else None,
                            "center_error_max": float(np.max(errs)) if errs else None,
                        }
                    )
                per_position.append(
                    {
                        "shape": shape,
                        "gv": gv,
                        "sensor": sensor,
                        "boundary": room.boundary.tolist(),
                        "positions": pos.tolist(),
                        "correct": dict(outcome),
                    }
                )
    bar.close()
    return {
        "cells": cells,
        "positions": per_position,
        "judge_time_median_ms": float(np.median(timings) * 1e3) if timings else None,
    }


def run_false_positives(
    *,
    seed: int = 0,
    per_room: int = 12,
    gv_distances: tuple[float, ...] = (3.0, 5.0),
    sensor: str = "paper_15m",
    progress: bool = True,
) -> dict[str, Any]:
    """Judge scans in the asymmetric rooms of :data:`FP_ROOMS`; count false positives.

    Each room is built at every G-V distance in ``gv_distances``, with ``per_room`` positions
    spread over all of them.
    """
    from symloc.sim.lidar import PRESETS, simulate_scan
    from symloc.symmetry import SymmetryConfig, judge_symmetry

    rng = as_rng(seed + 1)
    preset = PRESETS[sensor]
    cfg = SymmetryConfig.from_lidar(preset)
    by_cen: dict[str, dict[str, int]] = {c: {"count": 0, "trials": 0} for c in CENTROIDS}
    rows: list[dict[str, Any]] = []
    # spread per_room scans over the G-V distances (the first ones get the remainder)
    n_gv = len(gv_distances)
    counts = [per_room // n_gv + (i < per_room % n_gv) for i in range(n_gv)]
    total = len(FP_ROOMS) * per_room
    bar = tqdm(total=total, desc="false positives", file=sys.stderr, disable=not progress)
    for spec in FP_ROOMS:
        row: dict[str, Any] = {"room": spec.label, "true_order": spec.true_order, "trials": 0}
        row.update({f"fp_{c}": 0 for c in CENTROIDS})
        row.update({f"order_found_{c}": 0 for c in CENTROIDS})
        kinds: dict[str, int] = {}
        for gv, n_each in zip(gv_distances, counts, strict=True):
            if n_each == 0:
                continue
            room = _build_fp_room(spec, gv, rng)
            pos = room.positions_inside(n_each, margin=0.3)
            for p in pos:
                pose = np.array([p[0], p[1], rng.uniform(-math.pi, math.pi)])
                scan = simulate_scan(room.world, pose, preset, rng)
                row["trials"] += 1
                for cen in CENTROIDS:
                    rep = judge_symmetry(scan, config=cfg, centroid=cen)
                    claimed = rep.order if rep.symmetric else None  # k None: a circle
                    fp = claimed is not None and (
                        spec.true_order == 1 or claimed.k is None or claimed.k > spec.true_order
                    )
                    by_cen[cen]["count"] += int(fp)
                    by_cen[cen]["trials"] += 1
                    row[f"fp_{cen}"] += int(fp)
                    row[f"order_found_{cen}"] += int(
                        claimed == SymmetryOrder.finite(spec.true_order) and spec.true_order > 1
                    )
                    if cen == "area":
                        kinds[rep.kind] = kinds.get(rep.kind, 0) + 1
                bar.update(1)
        row["verdicts_area"] = kinds
        rows.append(row)
    bar.close()
    return {
        "sensor": sensor,
        "count": by_cen["area"]["count"],
        "trials": by_cen["area"]["trials"],
        "by_centroid": by_cen,
        "rooms": rows,
    }


def format_table(result: dict[str, Any], positions: int) -> str:
    """The printed tables: correct recognitions per cell, with the paper's figures."""
    lines: list[str] = []
    cells = result["cells"]
    sensors = sorted({c["sensor"] for c in cells}, key=SENSORS.index)
    gvs = sorted({c["gv"] for c in cells})
    shapes = [s for s in SHAPES if any(c["shape"] == s for c in cells)]
    for sensor in sensors:
        lines.append(f"\n## Table 1, sensor {sensor} (correct recognitions out of {positions})")
        head = f"{'room':<10} {'method':<19}" + "".join(f"  G-V {g:g} m" for g in gvs)
        lines.append(head)
        for shape in shapes:
            if sensor == "paper_15m" and shape in PAPER_TABLE1:
                paper = PAPER_TABLE1[shape]
                vals = [paper[GV_DISTANCES.index(g)] if g in GV_DISTANCES else "-" for g in gvs]
                lines.append(f"{shape:<10} {'paper':<19}" + "".join(f"  {v!s:>8}" for v in vals))
            for method in ("judge", "algorithm1"):
                for cen in CENTROIDS:
                    vals = []
                    for g in gvs:
                        hit = [
                            c
                            for c in cells
                            if c["sensor"] == sensor
                            and c["shape"] == shape
                            and c["gv"] == g
                            and c["method"] == method
                            and c["centroid"] == cen
                        ]
                        if hit:
                            unk = hit[0]["unknown"]
                            s = f"{hit[0]['correct']}" + (f"({unk}?)" if unk else "")
                        else:
                            s = "-"
                        vals.append(s)
                    label = f"{method}/{cen}"
                    lines.append(f"{shape:<10} {label:<19}" + "".join(f"  {v:>8}" for v in vals))
    lines.append("(N?) = N verdicts 'unknown' (e.g. walls beyond the sensor's range)")
    errs = [
        c
        for c in cells
        if c["method"] == "judge" and c["centroid"] == "area" and c["center_error_max"] is not None
    ]
    if errs:
        lines.append("\n## centre error of correct judgements (area centroid), world frame")
        for c in errs:
            lines.append(
                f"{c['sensor']:<11} {c['shape']:<9} G-V {c['gv']:g} m: median"
                f" {c['center_error_median'] * 1e3:.1f} mm, max {c['center_error_max'] * 1e3:.1f} mm"
            )
    return "\n".join(lines)


def format_false_positives(fp: dict[str, Any]) -> str:
    """The printed false-positive table."""
    lines = [f"\n## False positives on asymmetric rooms (sensor {fp['sensor']})"]
    lines.append(
        f"{'room':<26} {'order':>5} {'trials':>6} {'FP mean':>8} {'FP area':>8}"
        f" {'order-2 found (area)':>21}  verdicts (area)"
    )
    for r in fp["rooms"]:
        found = r["order_found_area"] if r["true_order"] > 1 else "-"
        lines.append(
            f"{r['room']:<26} {r['true_order']:>5} {r['trials']:>6} {r['fp_mean']:>8}"
            f" {r['fp_area']:>8} {found!s:>21}  {r['verdicts_area']}"
        )
    for cen, v in fp["by_centroid"].items():
        rate = 100.0 * v["count"] / max(v["trials"], 1)
        lines.append(f"total ({cen} centroid): {v['count']} / {v['trials']} = {rate:.2f} %")
    return "\n".join(lines)


def _run(args: argparse.Namespace) -> int:
    sensors = tuple(sorted(options.lidar_names(args.lidar), key=SENSORS.index))
    config = {
        "seed": args.seed,
        "positions": args.positions,
        "sensors": ",".join(sensors),
        "shapes": ",".join(SHAPES),
        "gv_distances_m": ",".join(f"{g:g}" for g in GV_DISTANCES),
        "false_positive_scans": args.fp_per_room * len(FP_ROOMS),
        "room_walls": "2.5 m, no lab (the paper's Gazebo rooms); margin 0.3 m from walls",
        "tolerances": "SymmetryConfig.from_lidar(preset): k_sigma=5 on data-sheet noise",
    }
    print_config("table1", config)
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    result = run_table1(seed=args.seed, positions=args.positions, sensors=sensors)
    print(format_table(result, args.positions))
    fp = run_false_positives(seed=args.seed, per_room=args.fp_per_room)
    print(format_false_positives(fp))
    if result["judge_time_median_ms"] is not None:
        print(f"\nmedian judgement time in this run: {result['judge_time_median_ms']:.3f} ms")
    data = {
        "config": config,
        "cells": result["cells"],
        "false_positives": fp,
        "paper": {k: list(v) for k, v in PAPER_TABLE1.items()},
        "positions": result["positions"],
    }
    write_json(args.json, data)
    write_results_file(
        args,
        clock,
        config,
        {
            "cells": result["cells"],
            "false_positives": fp,
            "paper": data["paper"],
            "judge_time_median_ms": result["judge_time_median_ms"],
        },
    )
    if not args.no_figure:
        from symloc.figures.symmetry import plot_table1_positions

        path = Path(args.out) / "table1_positions.png"
        shown = "paper_15m" if "paper_15m" in sensors else sensors[0]
        plot_table1_positions(result["positions"], path, sensor=shown)
        print(f"wrote {path}")
    return 0


def register(subparsers: Any) -> None:
    """Add ``symloc experiment table1``."""
    parser = subparsers.add_parser(
        "table1",
        help="Table 1: symmetry recognition in regular rooms (paper Sec. 5.1), plus false positives",
    )
    add_common_arguments(parser, "table1")
    parser.add_argument(
        "--positions",
        type=options.count,
        default=50,
        help="robot positions per room, an integer >= 1 (paper: 50)",
    )
    options.add_lidars(
        parser, help="simulated lidars (the paper's Table 1: paper_15m; all three: all)"
    )
    parser.add_argument(
        "--fp-per-room",
        type=options.count,
        default=12,
        help=f"scans per asymmetric room ({len(FP_ROOMS)} rooms; default 12 -> 204 scans)",
    )
    parser.add_argument("--no-figure", action="store_true", help="skip the PNG figure")
    options.add_results(parser, "docs/results/table1.json")
    parser.set_defaults(func=_run)
