"""symloc bench symmetry: judgements against the order computed from the geometry."""

from __future__ import annotations

import json
from pathlib import Path

from symloc.bench.symmetry_sweep import SymmetryTask, run_symmetry_world, summarize_symmetry
from symloc.bench.world_sources import WorldRef
from symloc.cli.main import main


def test_regular_polygons_are_judged_with_their_order() -> None:
    w = run_symmetry_world(SymmetryTask(WorldRef("builtin", "pentagon", 0), 0, poses=8))
    assert w["true_order"] == 5
    outcomes = [j["outcome"] for j in w["judgements"]]
    assert outcomes.count("correct") >= 7
    assert "false_symmetric" not in outcomes
    summary = summarize_symmetry([w])
    assert summary[-1]["family"] == "all"
    assert summary[-1]["judgements"] == 8


def test_cli_writes_the_table_and_json(tmp_path: Path) -> None:
    args = ["bench", "symmetry", "--families", "l_shape", "regular", "--seeds", "1", "--poses"]
    assert main([*args, "3", "--workers", "1", "--out", str(tmp_path)]) == 0
    doc = json.loads((tmp_path / "bench_symmetry.json").read_text())
    fams = {r["family"]: r for r in doc["summary"]}
    assert set(fams) == {"l_shape", "regular", "all"}
    assert fams["all"]["judgements"] == 6
    for r in doc["summary"]:
        assert (
            sum(r[o] for o in ("correct", "false_symmetric", "missed", "unknown"))
            == r["judgements"]
        )
