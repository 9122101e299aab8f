"""Benchmark: keyframe headings before and after their alignment with the images.

For each world (dev seeds of the generator's families), :func:`symloc.bench.scenario
.build_scenario` maps it with SLAM (one exploration lap, the ``realistic`` sensors) and records
keyframes with ``align_headings=True``: the SLAM headings are aligned with the relative headings
the keyframe images measure (:mod:`symloc.vision.rotation_averaging`) before they are stored.
The heading error of every keyframe against the truth in the map frame
(:attr:`Scenario.keyframe_true_poses`) is reported before (:attr:`Scenario.keyframe_slam_poses`)
and after (the stored headings): mean, 95th percentile and max of its absolute value [deg], its
mean (the part no relative measurement can fix: the gauge) and the wall time of the alignment
and of the whole mapping.

Run: ``python benchmarks/bench_keyframe_headings.py [--worlds circle:0 circle:1 ...]
[--json PATH] [--results docs/results/bench_keyframe_headings.json]`` (each world maps for
20-450 s); ``--results`` writes the results file the README's row is rendered from.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from symloc.bench.scenario import build_scenario
from symloc.bench.world_sources import WorldRef, build_world
from symloc.geometry import wrap_angle

WORLDS = ("circle:0", "circle:1", "regular:0", "regular:1", "rectangle:0", "rectangle:1")


def _stats(err_deg: np.ndarray) -> dict[str, float]:
    a = np.abs(err_deg)
    return {
        "mean": float(a.mean()),
        "p95": float(np.percentile(a, 95)),
        "max": float(a.max()),
        "bias": float(err_deg.mean()),
    }


SEED = 0
"""The scenario's seed (sensors, exploration) for every world."""


def run_world(family: str, seed: int) -> dict[str, Any]:
    """Map one world with aligned keyframe headings; the errors before and after [deg]."""
    ref = WorldRef("generated", family, seed)
    room = build_world(ref)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        scen = build_scenario(
            room,
            rng=SEED,
            workdir=Path(tmp),
            map_source="slam",
            explore_laps=1.0,
            regime="realistic",
            keyframes=True,
            align_headings=True,
        )
        seconds = time.perf_counter() - t0
        try:
            _, stored = scen.store.visual_map.keyframe_poses()
            truth = scen.keyframe_true_poses
            before = np.degrees(
                np.asarray(wrap_angle(scen.keyframe_slam_poses[:, 2] - truth[:, 2]))
            )
            after = np.degrees(np.asarray(wrap_angle(stored[:, 2] - truth[:, 2])))
            note = next((n for n in scen.notes if "keyframe headings:" in n), "")
        finally:
            scen.close()
    m = re.search(r"\(([\d.]+) s\)$", note)
    return {
        "world": f"{family}#{seed}",
        "keyframes": int(truth.shape[0]),
        "before": _stats(before),
        "after": _stats(after),
        "align_seconds": float(m.group(1)) if m else math.nan,
        "mapping_seconds": seconds,
        "note": note,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", nargs="+", default=list(WORLDS), help="family:seed ...")
    parser.add_argument("--json", type=Path, default=None, help="write the rows here")
    parser.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write the run's results file here (the README's: "
        "docs/results/bench_keyframe_headings.json): the rows with the command, commit, date, "
        "machine and load",
    )
    args = parser.parse_args()
    from symloc.bench.provenance import RunClock

    settings = {
        "seed": SEED,
        "worlds": " ".join(args.worlds),
        "scenario": "build_scenario(map_source='slam', explore_laps=1.0, regime='realistic', "
        "keyframes=True, align_headings=True)",
    }
    print("# bench_keyframe_headings")
    for key, value in settings.items():
        print(f"#   {key}: {value}")
    clock = RunClock()
    rows = []
    print(
        f"{'world':<13}{'N':>4}  {'before mean/p95/max [deg]':>26}  "
        f"{'after mean/p95/max [deg]':>25}  {'bias b/a':>11}  {'align s':>7}  {'map s':>6}"
    )
    for w in args.worlds:
        family, seed = w.split(":")
        r = run_world(family, int(seed))
        rows.append(r)
        b, a = r["before"], r["after"]
        print(
            f"{r['world']:<13}{r['keyframes']:>4}  "
            f"{b['mean']:>8.2f}{b['p95']:>8.2f}{b['max']:>8.2f}    "
            f"{a['mean']:>8.2f}{a['p95']:>8.2f}{a['max']:>8.2f}  "
            f"{b['bias']:>+5.2f}/{a['bias']:>+5.2f}  {r['align_seconds']:>7.1f}  "
            f"{r['mapping_seconds']:>6.0f}",
            flush=True,
        )
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=1))
    if args.results is not None:
        from symloc.bench.results_file import write_run_results

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


if __name__ == "__main__":
    main()
