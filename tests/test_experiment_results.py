"""``symloc experiment ... --results``: the README's paper table is rendered from these files.

Each command's results file must load (provenance present), record the command as typed and
the seed, and hold the figures the README's block reads (:mod:`symloc.bench.experiment_results`).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from symloc.bench.experiment_results import (
    AmclSymmetricFigures,
    BenchFigures,
    FiguresChangedError,
    KeyframesFigures,
    Table1Figures,
    expect,
    span,
)
from symloc.bench.results_file import load_results
from symloc.bench.shared_data import carmen_log_file, find_carmen_dir
from symloc.cli.main import main


def _run(tmp_path: Path, argv: list[str]) -> dict:
    results = tmp_path / "docs" / "results.json"
    argv = [*argv, "--out", str(tmp_path / "out"), "--results", str(results)]
    assert main(argv) == 0
    doc = load_results(results)
    assert doc["command"] == "symloc " + " ".join(argv)
    assert doc["settings"]["seed"] == 0
    assert doc["wall_s"] >= 0
    return doc


def test_table1_writes_its_cells_and_false_positives(tmp_path: Path) -> None:
    argv = ["experiment", "table1", "--lidar", "paper_15m", "--positions", "1"]
    doc = _run(tmp_path, [*argv, "--fp-per-room", "1", "--no-figure"])
    t1 = Table1Figures(doc)
    # 5 shapes x 3 G-V distances x 2 methods x 2 centroids, one position each
    assert len(t1.cells()) == 60
    assert len(t1.cells(method="judge", centroid="area")) == 15
    assert t1.counts(method="judge", centroid="area").endswith("/1")
    fp, scans = t1.false_positives()
    assert scans == 17
    assert 0 <= fp <= scans
    assert "positions" not in doc["figures"]  # the per-position lists stay in --json


def test_keyframes_writes_both_policies(tmp_path: Path) -> None:
    doc = _run(tmp_path, ["experiment", "keyframes"])
    kf = KeyframesFigures(doc)
    four, every5 = kf.policies()
    assert (four["count"], every5["count"]) == (4, 72)
    assert kf.ratio() == every5["bytes_features"] / four["bytes_features"] > 1


def test_amcl_symmetric_writes_one_row_per_room(tmp_path: Path) -> None:
    argv = ["experiment", "amcl-symmetric", "--trials", "1", "--rooms", "square"]
    doc = _run(tmp_path, [*argv, "--duration", "3"])
    sq = AmclSymmetricFigures(doc).room("square")
    assert sq["trials"] == 1
    assert sq["correct"] + sq["symmetric_copy"] + sq["not_converged"] == 1
    assert doc["settings"]["laser_model_type"] == "likelihood_field"
    with pytest.raises(FiguresChangedError, match="no room 'pentagon'"):
        AmclSymmetricFigures(doc).room("pentagon")


def test_span_and_expect() -> None:
    assert span([50, 40, 49], 50) == "40-50/50"
    assert span([50, 50]) == "50"
    with pytest.raises(FiguresChangedError):
        span([])
    assert expect("a figure", 0, 0) == ""
    with pytest.raises(FiguresChangedError, match="rewrite the sentence"):
        expect("LDS-01 wrong verdicts", 1, 0)


def test_table3_writes_its_matrix_and_counts(tmp_path: Path) -> None:
    from symloc.bench.experiment_results import Table3Figures

    doc = _run(tmp_path, ["experiment", "table3", "--trials", "1"])
    t3 = Table3Figures(doc)
    assert len(t3.figures["similarity"]) == 4
    lo, hi = t3.diagonal()
    assert 0 < lo <= hi
    assert t3.counts()["trials"] == 4
    assert t3.counts("untextured")["trials"] == 4


CARMEN = find_carmen_dir()  # $SYMLOC_SHARED_DATA/carmen or ../shared/data/carmen
HAS_ACES = CARMEN is not None and carmen_log_file(CARMEN, "aces").is_file()


@pytest.mark.skipif(
    not HAS_ACES,
    reason="shared CARMEN data not found (../shared/data/carmen or $SYMLOC_SHARED_DATA)",
)
def test_symmetry_carmen_writes_counts_without_index_lists(tmp_path: Path) -> None:
    argv = ["experiment", "symmetry-carmen", "--data", str(CARMEN), "--logs", "aces"]
    doc = _run(tmp_path, [*argv, "--stride", "50", "--no-figure"])
    aces = doc["figures"]["logs"]["aces"]
    assert doc["figures"]["n_judged"] == aces["n_judged"] == 9
    assert doc["figures"]["symmetric_strict"] == 0
    assert not any(k.endswith("_indices") for k in aces)


@pytest.mark.skipif(
    not HAS_ACES,
    reason="shared CARMEN data not found (../shared/data/carmen or $SYMLOC_SHARED_DATA)",
)
def test_amcl_carmen_writes_the_tracking_figures(tmp_path: Path) -> None:
    argv = ["experiment", "amcl-carmen", "--data", str(CARMEN), "--logs", "aces"]
    doc = _run(tmp_path, [*argv, "--skip-global"])
    (aces,) = doc["figures"]["logs"]
    assert aces["log"] == "aces"
    assert "global" not in aces  # --skip-global
    assert 0 < aces["tracking"]["mean_error_m"] < 1.0
    assert doc["settings"]["logs"] == "aces"


@pytest.mark.skipif(
    not HAS_ACES,
    reason="shared CARMEN data not found (../shared/data/carmen or $SYMLOC_SHARED_DATA)",
)
def test_amcl_carmen_keeps_the_logs_it_finished_when_a_later_one_fails(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import json

    from symloc.experiments import amcl_carmen

    real = amcl_carmen.log_data

    def fail_on_intel(name: str, *args: object, **kwargs: object) -> object:
        if name == "intel":
            raise RuntimeError("stopped while running intel")
        return real(name, *args, **kwargs)

    def quick_tracking(data: object, *args: object) -> dict:
        # the tracking itself is tested above; here only what is written when a log fails
        symloc = dict.fromkeys(
            ("claimed_scans", "scans", "mean_error_m", "p95_error_m", "p95_heading_error_deg"), 1
        )
        symloc |= dict.fromkeys(("outside_tolerance_scans", "confident_wrong_scans"), 0)
        symloc["outside_tolerance_reference_fits_worse"] = 0
        errors = dict.fromkeys(
            ("mean_error_m", "median_error_m", "p95_error_m", "max_error_m"), 0.05
        )
        errors |= {"mean_heading_error_deg": 1.0, "odometry_only_mean_error_m": 2.0}
        return {"_estimate": None, "symloc": symloc, **errors}

    monkeypatch.setattr(amcl_carmen, "log_data", fail_on_intel)
    monkeypatch.setattr(amcl_carmen, "tracking", quick_tracking)
    out = tmp_path / "partial.json"
    argv = ["experiment", "amcl-carmen", "--data", str(CARMEN), "--logs", "aces", "intel"]
    with pytest.raises(RuntimeError, match="intel"):
        main([*argv, "--skip-global", "--out", str(tmp_path / "out"), "--json", str(out)])
    doc = json.loads(out.read_text())
    assert doc["complete"] is False
    assert [e["log"] for e in doc["logs"]] == ["aces"]
    assert doc["logs"][0]["tracking"]["symloc"]["claimed_scans"] == 1


def _bench(name: str, date: str, wall_s: float | None) -> BenchFigures:
    doc = {
        "command": f"python benchmarks/{name}.py",
        "commit": "abc1234",
        "date": date,
        "machine": "2 cores",
        "load": "idle",
        "settings": {"seed": 0},
        "figures": {"rows": [{"what": "a", "ms": 1.0}, {"what": "b", "ms": 2.0}]},
        "wall_s": wall_s,
    }
    return BenchFigures(doc, name)


def test_bench_figures_rows_and_runs_that_went_on_together() -> None:
    soak = _bench("soak_node", "2026-11-28T17:09:00Z", 1800.0)
    during = _bench("bench_sim", "2026-11-28T16:50:00Z", 5.0)
    before = _bench("bench_symmetry", "2026-11-28T16:37:00Z", 3.0)
    undated = _bench("bench_x", "2026-11-28", 3.0)
    assert during.row(what="b")["ms"] == 2.0
    with pytest.raises(FiguresChangedError, match="no row"):
        during.rows(what="c")
    assert during.overlaps(soak)
    assert soak.overlaps(during)
    assert not before.overlaps(soak)
    assert not undated.overlaps(soak)
    assert "while `python benchmarks/soak_node.py` ran" in during.source(beside=[soak])
    assert "while" not in before.source(beside=[soak])
    assert "[docs/results/bench_sim.json](docs/results/bench_sim.json)" in during.source()
