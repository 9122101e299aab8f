"""Verdicts of ``judge_symmetry`` on seeded scans stay what they were (speed work guard).

``data/verdicts_seeded.json`` holds, for every scan of :func:`seeded_scans` (the benchmark's
rooms and the other bench rooms, three scanners, rooms of two sizes, seeded positions, headings and noise), the
verdict made by main bad82ae before the symmetry judgement was sped up: kind, order, number of
corners, centre and G-V distance [m]. The kind, order and corner count must be equal; the
centre and G-V distance equal to 1e-9 m (they were bit-identical on the machine that wrote the
file; another NumPy build may round its SIMD ``arctan2`` differently in the last bit).

Regenerate (only when a verdict is meant to change, saying why in the commit):
``PYTHONPATH=src python tests/symmetry/test_symmetry_verdicts_seeded.py --write``.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from symloc.scan import LaserScan
from symloc.sim.lidar import LDS01, PAPER_15M, RPLIDAR_A2, LidarPreset, simulate_scan
from symloc.sim.rooms import build_room
from symloc.symmetry import SymmetryConfig, judge_symmetry

FIXTURE = Path(__file__).parent / "data" / "verdicts_seeded.json"

#: (room name, furniture boxes, door, size factor): the benchmark's three rooms first.
ROOMS = (
    ("hexagon", 0, False, 1.0),
    ("circle", 0, False, 1.0),
    ("square", 1, False, 1.0),
    ("triangle", 0, False, 1.0),
    ("square", 0, False, 1.0),
    ("pentagon", 0, False, 1.0),
    ("octagon", 0, False, 1.0),
    ("rectangle", 0, False, 1.0),
    ("hallway", 0, False, 1.0),
    ("hallway", 0, False, 2.5),
    ("l_shaped", 0, False, 1.0),
    ("square", 0, True, 1.0),
    ("hexagon", 2, False, 1.0),
)
#: Scanners and the G-V distance [m] of the rooms each sees (the LDS-01 reaches 3.5 m).
PRESETS = ((PAPER_15M, 5.0), (RPLIDAR_A2, 5.0), (LDS01, 2.0))
POSITIONS = 10


def seeded_scans() -> list[tuple[str, LidarPreset, LaserScan]]:
    """``(label, preset, scan)`` for every room, scanner and seeded position."""
    out = []
    for r_i, (name, boxes, door, size) in enumerate(ROOMS):
        for preset, gv in PRESETS:
            room = build_room(name, gv * size, lab=False, furniture=boxes, door=door, rng=r_i)
            rng = np.random.default_rng(1000 * r_i + preset.n_beams)
            for j, p in enumerate(room.positions_inside(POSITIONS)):
                pose = np.r_[p, rng.uniform(-math.pi, math.pi)]
                label = f"{name}+{boxes}{'+door' if door else ''}x{size:g}/{preset.name}/{j}"
                out.append((label, preset, simulate_scan(room.world, pose, preset, rng)))
    return out


def verdicts() -> dict[str, dict[str, Any]]:
    """The verdict of every seeded scan, JSON-ready."""
    res = {}
    for label, preset, scan in seeded_scans():
        rep = judge_symmetry(scan, config=SymmetryConfig.from_lidar(preset))
        res[label] = {
            "kind": rep.kind,
            "order": None if rep.order is None else rep.order.to_json(),
            "corners": int(rep.corners.shape[0]),
            "center": [float(v) for v in rep.center],
            "gv_distance": float(rep.gv_distance),
        }
    return res


def _same_float(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or abs(a - b) <= 1e-9


def test_verdicts_on_seeded_scans_are_unchanged() -> None:
    want = json.loads(FIXTURE.read_text())
    got = verdicts()
    assert sorted(got) == sorted(want)
    kinds = {v["kind"] for v in want.values()}
    assert {"polygon", "circle", "asymmetric", "rectangle", "hallway"} <= kinds
    bad = []
    for label, w in want.items():
        g = got[label]
        same = (
            (g["kind"], g["order"], g["corners"]) == (w["kind"], w["order"], w["corners"])
            and all(_same_float(a, b) for a, b in zip(g["center"], w["center"], strict=True))
            and _same_float(g["gv_distance"], w["gv_distance"])
        )
        if not same:
            bad.append(f"{label}: {g} != {w}")
    assert not bad, "\n".join(bad[:10])


if __name__ == "__main__":
    if "--write" in sys.argv:
        FIXTURE.parent.mkdir(exist_ok=True)
        rows = [f"{json.dumps(k)}: {json.dumps(v, sort_keys=True)}" for k, v in verdicts().items()]
        FIXTURE.write_text("{\n" + ",\n".join(sorted(rows)) + "\n}\n")  # a scan per line
    else:
        json.dump(verdicts(), sys.stdout, indent=0, sort_keys=True)
