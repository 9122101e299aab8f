"""A run's provenance: the command as typed again, the commit, the machine, the load."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from symloc.bench.provenance import RunClock, command_line, commit, machine, utc_now


def test_command_line_is_what_a_shell_would_split_back() -> None:
    argv = ["bench", "localization", "--out", "my runs/a", "--seeds", "3"]
    line = command_line(argv)
    assert line.startswith("symloc bench localization")
    assert shlex.split(line)[1:] == argv


def test_commit_of_this_checkout_and_of_a_plain_folder(tmp_path: Path) -> None:
    here = commit()
    assert re.fullmatch(r"[0-9a-f]{7,40}(\+dirty)?|unknown \(not a git checkout\)", here)
    assert commit(tmp_path) == "unknown (not a git checkout)"


def test_machine_and_clock() -> None:
    m = machine()
    assert m["cpus"] >= 1
    assert m["python"].count(".") == 2
    assert m["numpy"].count(".") == 2
    # the SIMD targets are names NumPy dispatches to (a run's grades can follow them)
    assert all(isinstance(name, str) and name.isupper() for name in m["numpy_simd"])
    clock = RunClock()
    assert clock.wall_s is None
    clock.stop()
    first = clock.wall_s
    assert first is not None
    assert first >= 0.0
    assert clock.stop().wall_s == first  # the first stop counts
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", utc_now())
    assert clock.load()["cpus"] == m["cpus"]
    assert clock.revision == commit()


def test_a_pinned_benchmark_run_says_taskset(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from symloc.bench import provenance
    from symloc.bench.results_file import load_results, write_bench_results

    monkeypatch.setattr(provenance, "cpus_allowed", lambda: [0])
    argv = ["benchmarks/bench_x.py", "--seed", "0"]
    path = write_bench_results(
        tmp_path / "r.json", clock=RunClock(), settings={"seed": 0}, figures={"rows": []}, argv=argv
    )
    doc = load_results(path)
    assert doc["command"] == "taskset -c 0 python benchmarks/bench_x.py --seed 0"
    assert doc["settings"]["cpus_allowed"] == [0]
    monkeypatch.setattr(provenance, "cpus_allowed", lambda: None)
    path = write_bench_results(
        tmp_path / "r.json", clock=RunClock(), settings={"seed": 0}, figures={"rows": []}, argv=argv
    )
    assert load_results(path)["command"] == "python benchmarks/bench_x.py --seed 0"


def test_peer_source_reads_the_build_note_beside_the_program(tmp_path: Path) -> None:
    from symloc.bench.provenance import peer_source

    (tmp_path / "driver").write_text("", encoding="utf-8")
    assert peer_source(f"{tmp_path / 'driver'} --x", "stock") == "stock"
    (tmp_path / "SOURCE.txt").write_text("ROS 1 amcl 1.17.3 core\n", encoding="utf-8")
    assert peer_source(f"{tmp_path / 'driver'} --x", "stock") == "ROS 1 amcl 1.17.3 core"
    assert peer_source("", "stock") == "stock"
