"""Benchmark: a round room's keyframe headings, SLAM's against the gyro's with its drift fitted.

For each world (the bench's generator worlds, mapped as ``symloc bench localization`` maps them:
the world's own robot, realistic sensors, one lap and the stops to look around, keyframes), the
keyframes' heading and position errors against the truth in the map frame, as SLAM gave them
(:attr:`Scenario.keyframe_slam_poses`) and as stored (in a round room: the gyro-odometry's
headings with its bias and scale fitted to image pairs, :mod:`symloc.vision.gyro_drift`), and
the fit's own heading std (what the claim gate is told, ``ClaimConfig.map_rotation_std``) with
the share of keyframes whose heading error lies within 1.96 of it.

Run: ``python benchmarks/bench_round_room_headings.py [--worlds circle:0 circle:1 ...]
[--json PATH] [--no-prior]`` (each world maps for 1-6 minutes). ``--no-prior`` fits the drift
without the gyro data sheet's prior on its bias and scale (``DriftSettings.bias_std``,
``scale_std`` 0), as before 9e70c91, to compare the two on the same trips.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from symloc.bench import scenario
from symloc.bench.localization import bench_scenario
from symloc.bench.world_sources import WorldRef, build_world
from symloc.geometry import wrap_angle
from symloc.vision.gyro_drift import declared_rotation_std

WORLDS = ("circle:0", "circle:1")


def _errors(poses: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    head = np.degrees(np.asarray(wrap_angle(poses[:, 2] - truth[:, 2]), np.float64))
    pos = 100.0 * np.hypot(*(poses[:, :2] - truth[:, :2]).T)
    a = np.abs(head)
    return {
        "heading_mean_deg": float(a.mean()),
        "heading_p95_deg": float(np.percentile(a, 95)),
        "heading_max_deg": float(a.max()),
        "heading_bias_deg": float(head.mean()),
        "position_mean_cm": float(pos.mean()),
        "position_p95_cm": float(np.percentile(pos, 95)),
    }


def run_world(family: str, seed: int, split: str) -> dict[str, Any]:
    """Map one world as the localization bench does; the keyframes' errors before and after."""
    ref = WorldRef("generated", family, seed)
    room = build_world(ref)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        scen = bench_scenario(ref, room, Path(tmp), regime="realistic")
        seconds = time.perf_counter() - t0
        try:
            _, stored = scen.store.visual_map.keyframe_poses()
            truth = scen.keyframe_true_poses
            before = _errors(scen.keyframe_slam_poses, truth)
            after = _errors(np.asarray(stored, np.float64), truth)
            declared = declared_rotation_std(scen.store.visual_map)
            std = math.degrees(
                scen.settings.claim.map_rotation_std if declared is None else declared
            )
            head = np.abs(
                np.degrees(np.asarray(wrap_angle(stored[:, 2] - truth[:, 2]), np.float64))
            )
            note = next((n for n in scen.notes if "round-room keyframe headings" in n), "")
        finally:
            scen.close()
    return {
        "world": ref.world_id,
        "split": split,
        "keyframes": int(truth.shape[0]),
        "slam": before,
        "stored": after,
        "fitted": bool(note),
        "heading_std_deg": std,
        "within_1.96_std": float(np.mean(head <= 1.96 * std)),
        "mapping_seconds": seconds,
        "note": note,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", nargs="+", default=list(WORLDS), help="family:seed ...")
    parser.add_argument("--json", type=Path, default=None, help="write the rows here")
    parser.add_argument(
        "--no-prior", action="store_true", help="fit the drift without the data sheet's prior"
    )
    args = parser.parse_args()
    if args.no_prior:
        plain = scenario._drift_settings
        scenario._drift_settings = lambda gyro: dataclasses.replace(
            plain(gyro), bias_std=0.0, scale_std=0.0
        )
    print("# bench_round_room_headings")
    print("#   worlds:", " ".join(args.worlds))
    print("#   drift fit:", "without the prior" if args.no_prior else "with the data sheet's prior")
    print("#   scenario: symloc.bench.localization.bench_scenario(regime='realistic')")
    rows = []
    print(
        f"{'world':<14}{'N':>5}  {'SLAM |err| mean/p95/max deg':>28}  "
        f"{'stored |err| mean/p95/max deg':>30}  {'bias s/a':>11}  {'std':>5}  {'in 1.96':>7}"
    )
    for w in args.worlds:
        family, seed = w.split(":")
        split = "test" if int(seed) >= 1_000_000 else "dev"
        r = run_world(family, int(seed), split)
        rows.append(r)
        b, a = r["slam"], r["stored"]
        print(
            f"{r['world']:<14}{r['keyframes']:>5}  "
            f"{b['heading_mean_deg']:>9.2f}{b['heading_p95_deg']:>7.2f}{b['heading_max_deg']:>7.2f}"
            f"     {a['heading_mean_deg']:>11.2f}{a['heading_p95_deg']:>7.2f}"
            f"{a['heading_max_deg']:>7.2f}    {b['heading_bias_deg']:>+5.2f}/"
            f"{a['heading_bias_deg']:>+5.2f}  {r['heading_std_deg']:>5.2f}  "
            f"{r['within_1.96_std']:>7.2f}",
            flush=True,
        )
        if args.json is not None:  # partial results as they come
            args.json.write_text(json.dumps(rows, indent=1))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
