"""Benchmark scripts' ``--results PATH``: a small run writes a results file that the README's
blocks render from.

Each test runs one script of ``benchmarks/`` in a child process with a tiny input, checks the
file's provenance and rows, then puts it in place of the committed one in a copy of README.md
and ``docs/results`` and renders the copy (:func:`symloc.readme.render`): the README's block
must still render from a fresh file. No timing is asserted.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from symloc.bench.results_file import PROVENANCE, load_results

pytest.importorskip("cogapp", reason="cogapp renders the README's blocks (the [test] extra)")

from symloc.readme import render

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.slow


def run_bench(tmp_path: Path, script: str, *args: str) -> dict[str, Any]:
    """Run ``benchmarks/SCRIPT`` with ``args`` and ``--results``; return the file, validated."""
    out = tmp_path / "results.json"
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), *filter(None, [env.get("PYTHONPATH")])])
    proc = subprocess.run(
        [sys.executable, f"benchmarks/{script}", *args, "--results", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    doc = load_results(out)
    for key in PROVENANCE:
        assert doc[key], key
    assert doc["command"].split()[:2] in (["python", f"benchmarks/{script}"], ["taskset", "-c"])
    return doc


def renders_with(tmp_path: Path, name: str, doc_path: Path) -> str:
    """Render a copy of the README with ``doc_path`` as ``docs/results/NAME.json``; returns
    the rendered text."""
    copy = tmp_path / "readme"
    copy.mkdir()
    shutil.copy(ROOT / "README.md", copy / "README.md")
    shutil.copytree(ROOT / "docs" / "results", copy / "docs" / "results")
    shutil.copy(doc_path, copy / "docs" / "results" / f"{name}.json")
    render(copy / "README.md")
    return (copy / "README.md").read_text(encoding="utf-8")


def test_bench_symmetry_results(tmp_path: Path) -> None:
    doc = run_bench(tmp_path, "bench_symmetry.py", "--repeats", "2", "--rounds", "1")
    rows = doc["figures"]["rows"]
    assert {(r["beams"], r["room"]) for r in rows if r["method"] == "judge_symmetry"} == {
        (b, room) for b in (360, 800) for room in ("hexagon", "circle", "square+box")
    }
    assert all(r["cpu_ms"] > 0 for r in rows)
    text = renders_with(tmp_path, "bench_symmetry", tmp_path / "results.json")
    assert "--repeats 2 --rounds 1" in text


def test_bench_vision_results(tmp_path: Path) -> None:
    """With ``SYMLOC_DBOW3_DRIVER`` (benchmarks/peers/dbow3/build.sh's driver) the same-run rows
    are measured too and the README's block renders; without it only the file is checked."""
    driver = os.environ.get("SYMLOC_DBOW3_DRIVER")
    peer = ["--dbow3", driver] if driver else []
    doc = run_bench(tmp_path, "bench_vision.py", "--repeats", "2", "--clock", "cpu", *peer)
    rows = doc["figures"]["rows"]
    assert all(r["symloc_ms"] > 0 for r in rows)
    assert any(r["dbow3"] == "stored" for r in rows)
    if driver:
        same = [r for r in rows if r["dbow3"] == "same run"]
        assert len(same) == 3
        assert all(r["bow_vectors_equal"] == r["images"] for r in same)
        assert "--repeats 2" in renders_with(tmp_path, "bench_vision", tmp_path / "results.json")


def test_bench_amcl_update_results(tmp_path: Path) -> None:
    """With ``SYMLOC_AMCL_PEER`` and ``SYMLOC_AMCL_PEER_FAIR`` (benchmarks/peers/amcl_core's
    drivers) the peers run too and the README's block renders; without, symloc's rows only."""
    stock, fair = os.environ.get("SYMLOC_AMCL_PEER"), os.environ.get("SYMLOC_AMCL_PEER_FAIR")
    peers = ["--peer", stock, "--peer-fair", fair] if stock and fair else []
    args = ["--sizes", "300", "600", "--updates", "3", "--rounds", "1", *peers]
    doc = run_bench(tmp_path, "bench_amcl.py", *args)
    rows = doc["figures"]["rows"]
    assert {r["particles"] for r in rows} == {300, 600}
    assert all(r["cpu_ms_per_update"] > 0 for r in rows)
    if peers:
        assert {r["side"] for r in rows} == {"symloc", "C++", "C++ fair"}
        text = renders_with(tmp_path, "bench_amcl_update", tmp_path / "results.json")
        assert "--sizes 300 600" in text


def test_bench_fields_results(tmp_path: Path) -> None:
    doc = run_bench(tmp_path, "bench_fields.py", "--rows", "300", "--cols", "240")
    rows = doc["figures"]["rows"]
    assert [r["field"] for r in rows] == ["distance", "surface"]
    assert all(r["peak_mib"] >= r["before_mib"] > 0 for r in rows)
    assert "--rows 300 --cols 240" in renders_with(
        tmp_path, "bench_fields", tmp_path / "results.json"
    )


def test_bench_fields_replay_results(tmp_path: Path) -> None:
    args = ["--replay", str(tmp_path / "big"), "--rows", "300", "--cols", "300", "--scans", "2"]
    doc = run_bench(tmp_path, "bench_fields.py", *args)
    (row,) = doc["figures"]["rows"]
    assert row["exit_code"] in (0, 3)
    assert row["peak_rss_mib"] > 0
    assert set(row["sha256_16"]) == {"replay_scans.csv", "replay_scans.tum"}
    assert "--scans 2" in renders_with(tmp_path, "bench_fields_replay", tmp_path / "results.json")


def test_bench_first_scan_results(tmp_path: Path) -> None:
    doc = run_bench(tmp_path, "bench_first_scan.py", "--repeats", "1")
    rows = doc["figures"]["rows"]
    assert [r["cache"] for r in rows] == ["cold", "warm"]
    assert all(r["first_wall_s"] > 0 and isinstance(r["aot_kernels"], bool) for r in rows)
    assert "--repeats 1" in renders_with(tmp_path, "bench_first_scan", tmp_path / "results.json")


def test_bench_sim_results(tmp_path: Path) -> None:
    doc = run_bench(tmp_path, "bench_sim.py", "--repeats", "2")
    rows = doc["figures"]["rows"]
    assert any(r["what"] == "camera render 640x480" for r in rows)
    assert all(r["cpu_ms"] > 0 and r["target_ms"] > 0 for r in rows)
    assert set(doc["figures"]["orb_keypoints"]) == {"textured lab", "plain lab"}
    assert "--repeats 2" in renders_with(tmp_path, "bench_sim", tmp_path / "results.json")


def test_bench_global_search_results(tmp_path: Path) -> None:
    doc = run_bench(tmp_path, "bench_global_search.py", "--scans", "2", "--maps", "room")
    rows = doc["figures"]["rows"]
    assert [r["map"] for r in rows] == ["room l10", "room square10+box"]
    assert all(r["scans"] == 2 and r["cpu_ms_median"] > 0 for r in rows)
    text = renders_with(tmp_path, "bench_global_search", tmp_path / "results.json")
    assert "--scans 2 --maps room" in text


def test_soak_node_results(tmp_path: Path) -> None:
    args = ["--minutes", "0.05", "--window", "0.025", "--map-change", "1"]
    doc = run_bench(tmp_path, "soak_node.py", *args)
    verdict = doc["figures"]["verdict"]
    assert verdict["scans"] == sum(w["scans"] for w in doc["figures"]["rows"]) > 0
    assert verdict["maps_sent"] >= 1
    assert len(verdict["rss_mb_at_1min_max_end"]) == 3
    assert "--map-change 1" in renders_with(tmp_path, "soak_node", tmp_path / "results.json")
