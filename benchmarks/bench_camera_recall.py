"""Benchmark: how often the camera verifies the true pose, and only it, against the keyframes.

For each world (generator family and seed), :func:`symloc.bench.scenario.build_scenario` maps
it with SLAM (one exploration lap, ``realistic`` sensors) and records keyframes along the trip.
Then, at ``--views`` random poses inside the room (at random headings), the camera's image is
rendered and the keyframe store is asked to verify the true pose (in the map frame) among its
rotated copies about the map's symmetries (or, in an asymmetric map, the pose turned by half a
turn), once per ``max_distance`` setting of the verification. Reported per world and setting:

- truth verified: the true pose's check says *verified*;
- decided right / decided wrong: the store names the true pose / another one (with margin);
- nothing to compare: every hypothesis *unknown* (no expected keyframe, or an untextured view);
- the camera's heading error of a verified truth (its corrected heading against the true one)
  [deg]: median, 95th percentile, max;
- the wall time of one verification [ms].

Run: ``python benchmarks/bench_camera_recall.py [--worlds rhombus:0 regular:0 ...] [--views N]
[--distances 1 2] [--seed S] [--json PATH]`` (each world maps for 20-450 s).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from symloc.bench.scenario import build_scenario
from symloc.bench.world_sources import WorldRef, build_world
from symloc.geometry import wrap_angle
from symloc.localizer.copies import rotated_copies
from symloc.symmetry.order import SymmetryOrder

WORLDS = ("rhombus:0", "regular:0")


def _hypotheses(truth: np.ndarray, symmetries: list[Any]) -> np.ndarray:
    """The true pose (3,) first, then its rotated copies (K, 3)."""
    hyps = [truth]
    for sym in symmetries:
        hyps.extend(rotated_copies(truth, sym.centre, SymmetryOrder.finite(sym.order))[1:])
    if len(hyps) == 1:
        hyps.append(np.array([truth[0], truth[1], float(wrap_angle(truth[2] + math.pi))]))
    return np.array(hyps, dtype=np.float64)


def run_world(
    family: str, seed: int, views: int, distances: list[float], view_seed: int
) -> dict[str, Any]:
    """Map one world and verify ``views`` random true poses at each ``max_distance`` [m]."""
    ref = WorldRef("generated", family, seed)
    room = build_world(ref)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        scen = build_scenario(
            room,
            rng=ref.robot_seed,
            workdir=Path(tmp),
            map_source="slam",
            explore_laps=1.0,
            regime="realistic",
            keyframes=True,
        )
        mapped = time.perf_counter() - t0
        try:
            symmetries = scen.map_symmetries()
            rng = np.random.default_rng(view_seed)
            image = scen.image_at(rng)
            store = scen.store
            base = store.verification
            out: dict[str, Any] = {
                "world": f"{family}#{seed}",
                "keyframes": scen.n_keyframes,
                "map_symmetries": [(s.order, round(s.overlap, 3)) for s in symmetries],
                "mapping_s": mapped,
                "settings": {},
            }
            rows = {
                d: {"truth": 0, "right": 0, "wrong": 0, "none": 0, "err": [], "s": 0.0}
                for d in distances
            }
            for _ in range(views):
                pose = scen.random_pose(rng)
                img = image(pose)
                truth = scen.to_map(pose)
                hyps = _hypotheses(truth, symmetries)
                for d in distances:
                    store.verification = dataclasses.replace(base, max_distance=d)
                    t1 = time.perf_counter()
                    answer = store.verify(hyps, img)
                    rows[d]["s"] += time.perf_counter() - t1
                    checks = store.last_verification.checks
                    if checks[0].verified:
                        rows[d]["truth"] += 1
                        err = float(wrap_angle(checks[0].corrected_pose[2] - truth[2]))
                        rows[d]["err"].append(abs(math.degrees(err)))
                    if answer.index == 0:
                        rows[d]["right"] += 1
                    elif answer.index is not None:
                        rows[d]["wrong"] += 1
                    if all(c.status == "unknown" for c in checks):
                        rows[d]["none"] += 1
            store.verification = base
            for d, r in rows.items():
                err = np.asarray(r["err"])
                out["settings"][f"max_distance={d:g}"] = {
                    "views": views,
                    "truth_verified": r["truth"],
                    "decided_right": r["right"],
                    "decided_wrong": r["wrong"],
                    "nothing_to_compare": r["none"],
                    "heading_error_deg": None
                    if err.size == 0
                    else {
                        "median": float(np.median(err)),
                        "p95": float(np.percentile(err, 95)),
                        "max": float(err.max()),
                    },
                    "ms_per_verification": 1000.0 * r["s"] / views,
                }
            return out
        finally:
            scen.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", nargs="+", default=list(WORLDS), help="family:seed ...")
    parser.add_argument("--views", type=int, default=40, help="random views per world")
    parser.add_argument("--distances", type=float, nargs="+", default=[1.0, 2.0])
    parser.add_argument("--seed", type=int, default=7, help="seed of the random views")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    print(
        f"# bench_camera_recall: worlds {args.worlds}, views {args.views}, "
        f"max_distance {args.distances} m, view seed {args.seed}, regime realistic"
    )
    results = []
    for item in args.worlds:
        family, seed = item.split(":")
        res = run_world(family, int(seed), args.views, args.distances, args.seed)
        results.append(res)
        print(
            f"{res['world']}: {res['keyframes']} keyframes, map symmetries "
            f"{res['map_symmetries']}, mapped in {res['mapping_s']:.0f} s"
        )
        for name, r in res["settings"].items():
            h = r["heading_error_deg"]
            heading = (
                "-"
                if h is None
                else (f"median {h['median']:.2f} p95 {h['p95']:.2f} max {h['max']:.2f} deg")
            )
            print(
                f"  {name}: truth verified {r['truth_verified']}/{r['views']}, decided right "
                f"{r['decided_right']}, decided WRONG {r['decided_wrong']}, nothing to compare "
                f"{r['nothing_to_compare']}; heading error of a verified truth {heading}; "
                f"{r['ms_per_verification']:.0f} ms per verification",
                flush=True,
            )
        if args.json is not None:
            args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
