"""The README's quick-start figures are the demo's: ``symloc demo`` with its defaults prints the
table the README shows, line for line (a changed default, room or localizer shows here, not in
a user's first run)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from symloc.cli.main import main

ROOT = Path(__file__).resolve().parents[1]


def _readme_table() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    quick = text[text.index("## Quick start") : text.index("## Headline")]
    block = re.search(r"```\n(plain AMCL: what it did.*?)```", quick, re.S)
    assert block is not None, "README.md: no demo table under '## Quick start'"
    return block.group(1).strip().splitlines()


def test_demo_prints_the_readme_table(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out.splitlines()
    start = next(i for i, line in enumerate(out) if line.startswith("plain AMCL: what it did"))
    want = _readme_table()
    assert out[start : start + len(want)] == want
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    png = next(p.name for p in tmp_path.glob("demo_*.png"))
    assert f"symloc-demo/{png}" in readme  # the file the README names is the one written
