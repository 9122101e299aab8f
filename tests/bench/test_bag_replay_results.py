"""The results file of benchmarks/bench_bag_replay.py (symloc.bench.bag_replay_results)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from symloc.bench.bag_replay_results import (
    replay_counts,
    summary_row,
    within_targets,
    write_bag_replay_results,
)
from symloc.bench.provenance import RunClock
from symloc.bench.results_file import load_results

REPLAY_OUT = """# symloc replay bag
scans used: 906 of 910  status counts: {'tracking': 798, 'lost': 108}
dropped: {'odom: stamp went backwards': 4, 'scan: stamp went backwards': 4}
recording usable: 906 of 910 scans used (0.4 % dropped); 298 pauses
"""


def _row(log: str, replay: float, experiment: float, out: str = REPLAY_OUT) -> dict[str, Any]:
    """A row as bench_bag_replay.bench_log returns it (the figures it keeps)."""
    counts = replay_counts(out)
    assert counts is not None
    return {
        "log": log,
        "seed": 0,
        "scans": counts["scans"],
        "map_build_ate": 0.076,
        "build_map_ate": 0.08,
        "same_input_as_map_build": {
            "map_build_ate": 0.076,
            "build_map_ate": 0.0758,
            "difference": -0.0002,
        },
        "motion": {
            "rot1_over_half_rad_share": 0.4,
            "median_step_m": 0.67,
            "updates": 900,
            "heading_noise_over_twice_model_share": 0.0,
        },
        "dropped_share": 0.0,
        "dropped": replay_counts("scans used: 910 of 910\n"),
        "replay_all": {"n": 910, "mean": 0.15, "mean_aligned": 0.08, "rmse_aligned": 0.09},
        "replay_tracked": {"n": 800, "mean": 0.14, "mean_aligned": 0.07, "rmse_aligned": 0.08},
        "same_as_experiment": {
            "amcl_carmen_mean": experiment,
            "replay_mean": replay,
            "replay_n": counts["used"],
            "difference": replay - experiment,
            "dropped_share": counts["dropped_share"],
            "dropped": counts,
            "amcl_variants": {
                "as_run": {"mean_error_m": experiment, "max_error_m": 0.3},
                "every_scan": {"mean_error_m": float("nan"), "max_error_m": 0.2},
            },
        },
        "wall_s": 123.456,
    }


def test_replay_counts_reads_the_used_and_dropped_lines() -> None:
    c = replay_counts(REPLAY_OUT)
    assert c == {
        "used": 906,
        "scans": 910,
        "dropped": 4,
        "dropped_share": 4 / 910,
        "reasons": {"odom: stamp went backwards": 4, "scan: stamp went backwards": 4},
    }
    none = replay_counts("scans used: 440 of 440  status counts: {}\ndropped: {}\n")
    assert none is not None
    assert none["dropped"] == 0
    assert none["reasons"] == {}
    assert replay_counts("recording not usable: no scans") is None


def test_a_summary_row_keeps_the_paragraphs_figures_and_judges_the_targets() -> None:
    s = summary_row(_row("intel", 0.049, 0.0487))
    assert s["log"] == "intel"
    assert s["experiment_mean_m"] == 0.0487
    assert abs(s["difference_m"] - 0.0003) < 1e-12
    assert s["dropped"] == 4
    assert s["dropped_reasons"]["scan: stamp went backwards"] == 4
    assert s["within_targets"] is True  # 0.44 % dropped, 0.3 mm apart
    assert s["as_user"]["mean_aligned_m"] == 0.08
    assert s["as_user"]["dropped"] == 0
    assert s["build_map"]["difference_m"] == -0.0002
    assert s["motion"]["rot1_over_half_rad_share"] == 0.4
    assert s["motion"]["updates"] == 900
    assert s["amcl_variants"]["as_run"]["mean_error_m"] == 0.0487
    assert s["amcl_variants"]["every_scan"]["mean_error_m"] is None
    assert s["wall_s"] == 123.5
    lost = summary_row(_row("freiburg-079", 10.4, 6.45))
    assert lost["within_targets"] is False
    many = replay_counts("scans used: 90 of 100\n")
    assert many is not None
    assert not within_targets({"difference_m": 0.0, "dropped_share": many["dropped_share"]})
    assert not within_targets({"difference_m": None, "dropped_share": 0.0})


def test_the_results_file_has_its_provenance_and_one_row_per_log(tmp_path: Path) -> None:
    rows = [_row("intel", 0.049, 0.0487), _row("aces", float("nan"), 0.062)]
    path = write_bag_replay_results(
        tmp_path / "bench_bag_replay.json",
        rows,
        argv=["benchmarks/bench_bag_replay.py", "--logs", "intel", "aces"],
        clock=RunClock(),
        settings={"logs": ["intel", "aces"], "seeds": [0]},
    )
    doc = load_results(path)
    assert doc["command"] == "python benchmarks/bench_bag_replay.py --logs intel aces"
    assert doc["figures"]["targets"] == {"difference_m": 0.02, "dropped_share_below": 0.01}
    assert [r["log"] for r in doc["figures"]["rows"]] == ["intel", "aces"]
    aces = doc["figures"]["rows"][1]
    assert aces["replay_mean_m"] is None  # a failed replay is null, not NaN
    assert aces["within_targets"] is False
    assert doc["wall_s"] is not None
