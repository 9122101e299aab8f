"""``benchmarks/claim_calibration.py`` refuses malformed worlds and a missing file by name,
before it maps anything."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), *filter(None, [env.get("PYTHONPATH")])])
    return subprocess.run(
        [sys.executable, "benchmarks/claim_calibration.py", *args],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.mark.parametrize(
    ("world", "said"),
    [
        ("corridor_short:0", "expected FAMILY:WORLD_SEED:TRIALS"),
        ("kitchen:0:0-1", "FAMILY 'kitchen' is not a generated family"),
        ("regular:zero:0-1", "WORLD_SEED an integer >= 0"),
        ("regular:0:a-b", "TRIALS as a-b or a,b,c"),
        ("regular:0:5-2", "TRIALS as a-b or a,b,c"),
        ("regular:-1:0", "WORLD_SEED an integer >= 0"),
    ],
)
def test_a_malformed_world_is_refused_by_name(tmp_path: Path, world: str, said: str) -> None:
    out = tmp_path / "claims.jsonl"
    proc = _run("--out", str(out), world)
    assert proc.returncode == 2
    assert f"world {world!r}" in proc.stderr
    assert said in proc.stderr
    assert not out.exists()  # nothing was run or written


def test_analyse_needs_the_file(tmp_path: Path) -> None:
    out = tmp_path / "missing.jsonl"
    proc = _run("--analyse", "--out", str(out))
    assert proc.returncode == 2
    assert f"--out {out}" in proc.stderr
    assert "existing JSON-lines file" in proc.stderr
