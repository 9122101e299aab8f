"""``symloc experiment table2 --results``: the README's Table 2 cell comes from this file."""

from __future__ import annotations

from pathlib import Path

import pytest

from symloc.bench.results_file import load_results
from symloc.cli.main import main


def test_table2_writes_a_results_file_with_its_provenance(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    results = tmp_path / "docs" / "table2.json"
    argv = ["experiment", "table2", "--lidar", "rplidar_a2", "--positions", "2"]
    argv += ["--out", str(tmp_path / "out"), "--results", str(results)]
    assert main(argv) == 0
    doc = load_results(results)
    assert doc["command"] == "symloc " + " ".join(argv)
    assert doc["settings"]["positions"] == 2
    assert doc["settings"]["seed"] == 0
    (row,) = doc["figures"]["results"]
    assert row["preset"] == "rplidar_a2"
    assert row["trials"] == 2
    assert set(row["shares"]) == {"5", "10", "15"}
    assert "errors_mm" not in row  # the per-run list stays out of the compact file
    assert doc["wall_s"] > 0
    # what the command printed is what the file holds
    printed = next(ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("rplidar_a2"))
    assert printed.split()[1] == f"{100 * row['shares']['5']:.0f}"
