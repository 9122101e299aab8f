"""``symloc map build`` and ``symloc experiment slam`` end to end (small runs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from symloc.cli.main import main
from symloc.grid.map_io import load_map, read_map_yaml


def test_map_build_world_writes_map_server_files(tmp_path: Path, capsys) -> None:
    code = main(["map", "build", "--world", "square", "--laps", "1.1", "--out", str(tmp_path)])
    assert code == 0
    out = capsys.readouterr().out
    assert "seed 0" in out
    assert "ATE RMSE" in out
    assert "map agreement" in out
    grid = load_map(tmp_path / "map.yaml")
    assert read_map_yaml(tmp_path / "map.yaml").image.is_file()  # map.<write id>.pgm
    assert (tmp_path / "map_trajectory.png").is_file()
    assert grid.resolution == pytest.approx(0.05)
    assert np.count_nonzero(grid.data == 100) > 100  # the board walls
    assert np.count_nonzero(grid.data == 0) > 1000  # the room's free floor


def test_map_build_missing_log(tmp_path: Path, capsys) -> None:
    code = main(["map", "build", "--carmen", str(tmp_path / "none.log"), "--out", str(tmp_path)])
    assert code == 2
    err = capsys.readouterr().err
    assert f"symloc: error: --carmen {tmp_path / 'none.log'}: not found" in err


def test_experiment_slam_rejects_unknown_world(tmp_path: Path, capsys) -> None:
    code = main(["experiment", "slam", "--worlds", "attic", "--logs", "--out", str(tmp_path)])
    assert code == 2
    assert "world: expected one of" in capsys.readouterr().err


def test_map_build_writes_how_the_map_was_made_into_its_yaml(tmp_path: Path) -> None:
    import yaml

    code = main(["map", "build", "--world", "square", "--laps", "1.1", "--out", str(tmp_path)])
    assert code == 0
    meta = yaml.safe_load((tmp_path / "map.yaml").read_text())["symloc_slam"]
    assert meta["scans"] > 10
    assert isinstance(meta["doubtful"], bool)
    assert meta["doubtful"] == bool(meta["warnings"])
    load_map(tmp_path / "map.yaml")  # map readers ignore the extra key


def test_map_build_prints_the_ate_without_timestamps_and_explains_doubtful(
    tmp_path: Path, capsys, monkeypatch
) -> None:
    """A log without usable timestamps still gets its ATE printed (the speed says why it is
    missing), and a doubtful result says what that means and what to do."""
    import dataclasses

    import symloc.bench.slam_runs as slam_runs

    real = slam_runs.run_simulated

    def no_clock_and_doubtful(*args, **kwargs):  # type: ignore[no-untyped-def]
        run = real(*args, **kwargs)
        summary = run.summary()
        summary["realtime_factor_cpu"] = float("nan")
        doubtful = dataclasses.replace(run.result, warnings=["no loop closure accepted"])
        out = dataclasses.replace(run, result=doubtful)
        monkeypatch.setattr(type(out), "summary", lambda self: summary)
        return out

    monkeypatch.setattr(slam_runs, "run_simulated", no_clock_and_doubtful)
    code = main(["map", "build", "--world", "square", "--laps", "1.1", "--out", str(tmp_path)])
    assert code == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("scans "))
    assert "ATE RMSE" in line
    assert "speed: no usable timestamps" in line
    assert "result DOUBTFUL" in out
    assert "DOUBTFUL: SLAM saw signs" in out
    assert "What to do" in out
