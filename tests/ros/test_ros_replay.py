"""A recorded simulated kidnapped-robot run: the bag round-trips and its replay matches the run."""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from symloc.bench.sim_record import SimRecording, record_sim_run
from symloc.errors import ConfigurationError
from symloc.io.rosbag import read_bag
from symloc.ros.params import NodeParams
from symloc.ros.replay import replay_bag


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> SimRecording:
    out = tmp_path_factory.mktemp("rec") / "run"
    return record_sim_run(out, room="square", seed=11, max_time=40.0)


def test_recorded_run_localizes_the_kidnapped_robot(recording: SimRecording) -> None:
    assert recording.final.status.value == "tracking"
    pos_err, head_err = recording.final_error
    assert pos_err < 0.1
    assert head_err < math.radians(5.0)
    assert recording.dropped == {}
    assert any("decided direction" in s for s in recording.steps)
    assert recording.counts["/camera/image_raw"] >= 1


def test_bag_round_trip_of_the_recording(recording: SimRecording) -> None:
    msgs = list(read_bag(recording.bag))
    kinds = Counter(m.kind for m in msgs)
    assert kinds["scan"] == len(recording.trajectory)
    assert kinds["truth"] == len(recording.truth)
    assert kinds["map"] == 1
    assert kinds["image"] == recording.counts["/camera/image_raw"]
    truth = np.array([[m.stamp, *m.value.pose] for m in msgs if m.kind == "truth"])
    np.testing.assert_allclose(truth, recording.truth, atol=1e-9)
    tum = (recording.assets / "truth.tum").read_text().splitlines()
    assert len(tum) == len(recording.truth)
    assert len(tum[0].split()) == 8


def test_replay_matches_the_in_process_run(recording: SimRecording) -> None:
    params = NodeParams.from_yaml(recording.params_path)
    res = replay_bag(recording.bag, params)
    assert len(res.trajectory) == len(recording.trajectory)
    assert [p.status for p in res.trajectory] == [p.status for p in recording.trajectory]
    for got, want in zip(res.trajectory, recording.trajectory, strict=True):
        assert got.stamp == pytest.approx(want.stamp, abs=1e-9)
        if want.pose is None:
            assert got.pose is None
        else:
            np.testing.assert_allclose(got.pose, want.pose, atol=1e-9)
    assert res.dropped == {}


def test_replay_cli_writes_tum_and_png(
    recording: SimRecording, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from symloc.cli.main import main

    out = tmp_path / "replay"
    argv = ["replay", str(recording.bag), "--params", str(recording.params_path), "--out", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "final: tracking" in text
    assert f"seed: {recording.params.seed}" in text  # the params' seed unless --seed is given
    tracked = (out / "replay.tum").read_text().splitlines()
    assert tracked
    assert len(tracked[0].split()) == 8
    # every scan's estimate (evo sees the whole run) and every scan's status
    every = (out / "replay_scans.tum").read_text().splitlines()
    assert len(every) == len(recording.trajectory) > len(tracked)
    assert all(len(line.split()) == 8 for line in every)
    rows = (out / "replay_scans.csv").read_text().splitlines()
    assert rows[0].startswith("stamp,status,tracked,x,y,theta_deg")
    assert len(rows) == 1 + len(recording.trajectory)
    statuses = [r.split(",")[1] for r in rows[1:]]
    assert statuses == [p.status for p in recording.trajectory]
    assert sum(int(r.split(",")[2]) for r in rows[1:]) == len(tracked)
    assert (out / "replay.png").stat().st_size > 10_000


def test_replay_without_a_visual_map_says_so(
    recording: SimRecording, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The square is symmetric: with no visual map no pose is earned, and the command says so
    (exit code 3) instead of writing an empty TUM and exiting 0."""
    from symloc.cli.main import main

    map_yaml = recording.assets / "map.yaml"
    out = tmp_path / "nomap"
    assert main(["replay", str(recording.bag), "--map", str(map_yaml), "--out", str(out)]) == 3
    captured = capsys.readouterr()
    assert "without a visual map a symmetric room cannot be resolved" in captured.out
    assert "no pose was earned" in captured.err
    assert "--visual-map" in captured.err
    assert (out / "replay.tum").read_text() == ""
    assert (out / "replay_scans.tum").read_text().strip()


def test_record_refuses_existing_paths(tmp_path: Path) -> None:
    (tmp_path / "run").mkdir()
    with pytest.raises(ConfigurationError, match="exists already"):
        record_sim_run(tmp_path / "run")
    (tmp_path / "b_assets").mkdir()
    (tmp_path / "b_assets" / "x").write_text("x")
    with pytest.raises(ConfigurationError, match="not empty"):
        record_sim_run(tmp_path / "b")


def test_sim_record_cli_mcap_compressed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from symloc.cli.main import main

    out = tmp_path / "rec"
    argv = ["sim", "record", "--out", str(out), "--format", "mcap", "--compressed", "--seed", "5"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "seed=5" in text
    assert "/camera/image_raw/compressed" in text
    assert "final: tracking" in text
    assert list((out / "run").glob("*.mcap"))
    assert (out / "assets" / "params.yaml").is_file()
    assert f"symloc replay {out / 'run'} --params {out / 'assets' / 'params.yaml'}" in text
    assert main(argv) == 2  # the folder is not empty now
    assert "not an empty folder" in capsys.readouterr().err
    images = [m for m in read_bag(out / "run") if m.kind == "image"]
    assert images
    assert images[0].value.shape == (480, 640, 3)
