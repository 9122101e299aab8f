from __future__ import annotations

import json
from pathlib import Path

import pytest

from symloc.cli.main import main
from symloc.experiments.table1 import FP_ROOMS, run_false_positives, run_table1


def test_table1_small_run_json_and_figure(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "t1.json"
    code = main(
        [
            "experiment",
            "table1",
            "--seed",
            "3",
            "--positions",
            "2",
            "--lidar",
            "paper_15m",
            "--fp-per-room",
            "1",
            "--json",
            str(out),
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    printed = capsys.readouterr().out
    assert "seed: 3" in printed
    assert "Table 1, sensor paper_15m" in printed
    data = json.loads(out.read_text())
    cells = data["cells"]
    assert {c["shape"] for c in cells} == {"triangle", "square", "pentagon", "hexagon", "circle"}
    for c in cells:
        assert set(c) >= {"shape", "gv", "sensor", "centroid", "correct", "trials"}
        assert c["trials"] == 2
        assert 0 <= c["correct"] <= 2
    area = [c for c in cells if c["method"] == "judge" and c["centroid"] == "area"]
    assert sum(c["correct"] for c in area) == 2 * len(area)
    fp = data["false_positives"]
    assert fp["trials"] == len(FP_ROOMS)
    assert fp["count"] == 0
    assert (tmp_path / "table1_positions.png").stat().st_size > 1000


def test_table1_is_reproducible_and_rejects_bad_positions(
    capsys: pytest.CaptureFixture[str],
) -> None:
    a = run_table1(
        seed=5,
        positions=1,
        sensors=("rplidar_a2",),
        shapes=("square",),
        gv_distances=(3.0,),
        progress=False,
    )
    b = run_table1(
        seed=5,
        positions=1,
        sensors=("rplidar_a2",),
        shapes=("square",),
        gv_distances=(3.0,),
        progress=False,
    )
    assert a["cells"] == b["cells"]
    fp = run_false_positives(seed=1, per_room=1, gv_distances=(3.0,), progress=False)
    assert fp["trials"] == len(FP_ROOMS)
    for flag in ("--positions", "--fp-per-room"):
        with pytest.raises(SystemExit) as exc:
            main(["experiment", "table1", flag, "0"])
        assert exc.value.code == 2
        assert f"{flag}: expected an integer >= 1" in capsys.readouterr().err


def test_unknown_false_positive_family_is_rejected() -> None:
    import numpy as np

    from symloc.errors import ConfigurationError
    from symloc.experiments.table1 import FPRoom, _build_fp_room

    with pytest.raises(ConfigurationError, match=r"FPRoom.family: expected .* got 'blob'"):
        _build_fp_room(FPRoom("blob 1", "blob", 1), 3.0, np.random.default_rng(0))


def test_plot_judgement_writes_a_png(tmp_path: Path) -> None:
    import numpy as np

    from symloc.figures.symmetry import plot_judgement
    from symloc.sim.lidar import PAPER_15M, simulate_scan
    from symloc.sim.rooms import build_room
    from symloc.symmetry import judge_symmetry

    room = build_room("pentagon", 3.0, lab=False)
    scan = simulate_scan(room.world, np.array([0.5, 0.2, 0.1]), PAPER_15M, 0)
    out = plot_judgement(scan, judge_symmetry(scan), tmp_path / "j.png")
    assert out.stat().st_size > 1000
