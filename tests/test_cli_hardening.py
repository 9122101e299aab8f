"""No silent success and no traceback at the command line: missing data sets fail before any
work, errors go to stderr as ``symloc: error: ...``, numeric bounds reach the library and the
node's parameters, maps on the topic are capped like map files."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from symloc.cli.main import main
from symloc.errors import ConfigurationError, DataFormatError


def _carmen(path: Path, scans: int = 3) -> Path:
    lines = []
    for i in range(scans):
        ranges = " ".join(f"{2.0 + 0.001 * j:.3f}" for j in range(180))
        pose = f"{0.1 * i:.2f} 0 0"
        lines.append(f"FLASER 180 {ranges} {pose} {pose} {1.0 + i} host {1.0 + i}")
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def no_shared_data(monkeypatch: pytest.MonkeyPatch) -> None:
    import symloc.bench.shared_data as shared

    monkeypatch.setattr(shared, "find_carmen_dir", lambda: None)


@pytest.mark.parametrize(
    "argv",
    [
        ["experiment", "slam", "--worlds", "--logs", "intel", "aces"],
        ["experiment", "slam", "--worlds"],  # the default logs, not on this machine
        ["experiment", "amcl-carmen", "--logs", "intel"],
        ["experiment", "symmetry-carmen", "--logs", "aces"],
        ["bench", "slam", "--logs", "intel"],
    ],
    ids=" ".join,
)
def test_nothing_requested_can_run_is_an_error_not_a_skip(
    argv: list[str],
    no_shared_data: None,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert "symloc: error:" in captured.err
    assert "not found" in captured.err or "nothing to run" in captured.err
    assert "Traceback" not in captured.err
    assert not list(tmp_path.iterdir()), "nothing may be written"


def test_named_logs_missing_from_data_are_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data"
    data.mkdir()
    _carmen(data / "intel-corrected.log.gz".removesuffix(".gz"))  # not the expected name
    code = main(["experiment", "slam", "--worlds", "--logs", "intel", "aces", "--data", str(data)])
    assert code == 2
    err = capsys.readouterr().err
    assert f"--logs: not found in {data}: intel (intel-corrected.log.gz)" in err
    assert "aces (aces-corrected.log.gz)" in err


def test_the_default_logs_are_skipped_with_a_warning_when_worlds_remain(
    no_shared_data: None,
) -> None:
    import argparse

    from symloc.experiments.slam import _requested_logs

    args = argparse.Namespace(logs=None, data=None)
    assert _requested_logs(args) == {}
    with pytest.raises(ConfigurationError, match="the CARMEN logs were not found"):
        _requested_logs(argparse.Namespace(logs=["intel"], data=None))


def test_map_build_errors_go_to_stderr_with_the_prefix(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["map", "build", "--carmen", str(tmp_path / "nope.log"), "--out", str(tmp_path)])
    assert code == 2
    captured = capsys.readouterr()
    assert f"symloc: error: --carmen {tmp_path / 'nope.log'}: not found" in captured.err
    assert "error:" not in captured.out
    code = main(["map", "build", "--world", "square", "--odometry", "log"])
    assert code == 2
    assert "symloc: error: --odometry log needs a CARMEN log" in capsys.readouterr().err


def test_a_negative_index_counts_from_the_end_of_a_carmen_log(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = _carmen(tmp_path / "t.log")
    js = tmp_path / "r.json"
    assert (
        main(["symmetry", "judge", "--carmen", str(log), "--index", "-1", "--json", str(js)]) == 0
    )
    import json

    assert json.loads(js.read_text())["index"] == 2
    assert main(["symmetry", "judge", "--carmen", str(log), "--index", "-4"]) == 2
    assert "expected -3 <= N < 3" in capsys.readouterr().err


def test_an_unwritable_output_after_the_checks_is_a_clean_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """/proc passes os.access for root but refuses new folders: the file system's refusal ends
    as a ``symloc: error`` line, not a traceback."""
    log = _carmen(tmp_path / "t.log")
    code = main(["symmetry", "judge", "--carmen", str(log), "--json", "/proc/no/such/r.json"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("symloc: error: /proc/no") or "argument --json" in err
    assert "Traceback" not in err


# ----------------------------------------------------------------------- parameters and the node


def test_max_particles_has_an_upper_bound_in_params_files(tmp_path: Path) -> None:
    from symloc.mcl.params import MAX_PARTICLES, AmclParams
    from symloc.ros.params import NodeParams

    text = "symloc:\n  ros__parameters:\n    amcl:\n      max_particles: 1000000000\n"
    with pytest.raises(ConfigurationError, match=r"max_particles: expected at most 4,000,000"):
        NodeParams.from_yaml(text)
    assert AmclParams(max_particles=MAX_PARTICLES).max_particles == MAX_PARTICLES
    params = tmp_path / "p.yaml"
    params.write_text(text)
    assert main(["ros", "check-params", str(params)]) != 0


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("max_map_cells", 2**40, "max_map_cells: expected an integer in [1, 67,108,864]"),
        ("max_image_pixels", 10**12, "max_image_pixels: expected an integer in [1, 50,000,000]"),
    ],
)
def test_node_size_caps_are_bounded(name: str, value: int, message: str) -> None:
    from symloc.ros.params import NodeParams

    with pytest.raises(ConfigurationError) as exc:
        NodeParams(**{name: value})
    assert message in str(exc.value)


def _map_msg(width: int, height: int, data: object) -> SimpleNamespace:
    pose = SimpleNamespace(
        position=SimpleNamespace(x=0.0, y=0.0, z=0.0),
        orientation=SimpleNamespace(x=0.0, y=0.0, z=0.0, w=1.0),
    )
    return SimpleNamespace(
        header=SimpleNamespace(stamp=SimpleNamespace(sec=1, nanosec=0), frame_id="map"),
        info=SimpleNamespace(width=width, height=height, resolution=0.05, origin=pose),
        data=data,
    )


def test_maps_on_the_topic_are_capped_before_their_data_is_read() -> None:
    from symloc.msgs.grid import grid_from_msg
    from symloc.ros.core import NodeCore
    from symloc.ros.params import NodeParams

    class Untouchable:
        def __len__(self) -> int:
            raise AssertionError("the data of a map over the cap was read")

    with pytest.raises(DataFormatError, match=r"12000 x 12000 = 144,000,000 cells; at most"):
        grid_from_msg(_map_msg(12000, 12000, Untouchable()))
    core = NodeCore(NodeParams(max_map_cells=30 * 30))
    core.on_map(_map_msg(40, 40, [0] * 1600))
    assert core.grid is None
    assert any("map: malformed" in k for k in core.dropped), dict(core.dropped)
    d = np.zeros((30, 30), np.int8)
    d[[0, -1], :] = 100
    d[:, [0, -1]] = 100
    core.on_map(_map_msg(30, 30, d.reshape(-1).tolist()))
    assert core.grid is not None
    assert core.grid.width == 30
    assert math.isclose(core.grid.resolution, 0.05)


# ----------------------------------------------------------------------- bags


def _bag_with_a_bad_scan(folder: Path, bad: int = 3, scans: int = 20) -> Path:
    """A ROS 2 (.db3) bag whose scan number ``bad`` carries 16 trailing bytes."""
    import sqlite3

    from symloc.grid import OccupancyGrid
    from symloc.io.rosbag import BagWriter
    from symloc.odometry import OdometryReading
    from symloc.scan import LaserScan

    path = folder / "bag"
    d = np.zeros((40, 40), np.int8)
    d[[0, -1], :] = 100
    d[:, [0, -1]] = 100
    with BagWriter(path, "ros2") as w:
        w.write_map(OccupancyGrid(d, 0.05), 0.0)
        for i in range(scans):
            t = 1 + 0.1 * i
            w.write_odometry(OdometryReading(np.array([0.01 * i, 0, 0]), t))
            w.write_scan(LaserScan(-math.pi, 2 * math.pi / 90, 0.1, 8, np.full(90, 0.9), stamp=t))
    db = next(path.glob("*.db3"))
    with sqlite3.connect(db) as con:
        (topic,) = con.execute("SELECT id FROM topics WHERE name = '/scan'").fetchone()
        mid, data = con.execute(
            "SELECT id, data FROM messages WHERE topic_id = ? ORDER BY timestamp LIMIT 1 OFFSET ?",
            (topic, bad),
        ).fetchone()
        con.execute("UPDATE messages SET data = ? WHERE id = ?", (data + bytes(16), mid))
    return path


def test_an_undecodable_bag_message_is_skipped_and_counted_not_the_rest(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    from collections import Counter

    from symloc.io.rosbag import read_bag

    path = _bag_with_a_bad_scan(tmp_path)
    dropped: Counter[str] = Counter()
    with caplog.at_level("DEBUG", logger="symloc.io.rosbag"):
        kinds = Counter(m.kind for m in read_bag(path, on_error="skip", dropped=dropped))
    assert kinds == Counter({"odom": 20, "scan": 19, "map": 1})
    assert dropped == Counter({"/scan": 1})
    # each skip at DEBUG, then one summary line: the count per topic and the first reason
    assert [r.levelname for r in caplog.records] == ["DEBUG", "WARNING"]
    summary = caplog.records[-1].getMessage()
    assert summary.startswith(f"bag {path}: skipped 1 undecodable message(s): /scan 1 (first at")
    assert "size mismatch" in summary
    with pytest.raises(DataFormatError, match="topic /scan at log time"):
        list(read_bag(path, on_error="raise"))


def test_replay_names_a_visual_map_that_is_not_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _bag_with_a_bad_scan(tmp_path)
    not_a_map = tmp_path / "README.md"
    not_a_map.write_text("# not a database\n" * 50)
    code = main(["replay", str(path), "--visual-map", str(not_a_map), "--out", str(tmp_path / "o")])
    assert code == 2
    err = capsys.readouterr().err
    assert f"symloc: error: visual_map: {not_a_map}: not a symloc visual map" in err
    assert not (tmp_path / "o").exists()
