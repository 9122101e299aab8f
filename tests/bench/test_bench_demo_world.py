"""``symloc demo --world FILE`` runs a user's floor plan end to end."""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

import pytest

from symloc.cli.main import main


def test_demo_on_a_world_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    world = str(files("symloc") / "data" / "worlds" / "square_with_box.yaml")
    assert main(["demo", "--world", world, "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "world " + world in out
    assert "symloc: verdict" in out
    assert (tmp_path / "demo_square-with-box.png").stat().st_size > 10_000


def test_demo_rejects_a_bad_world_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "w.yaml"
    bad.write_text("name: w\nroom:\n  regular: {n: 2, gv: 3}\n")
    assert main(["demo", "--world", str(bad), "--out", str(tmp_path)]) == 2
    assert "room.regular" in capsys.readouterr().err


def test_demo_untextured_runs_without_keyframes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Plain lab walls: the mapping trip records no keyframe (nothing for ORB to see); the demo
    says what happened instead of an IndexError (found by the command-line fuzz)."""
    assert main(["demo", "--room", "square", "--untextured", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "untextured lab" in out
    assert "symloc: verdict" in out
    assert (tmp_path / "demo_square.png").stat().st_size > 10_000


def test_untextured_overrides_the_world_file_s_lab(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--untextured`` with a world file whose lab is textured: plain walls, so the mapping
    trip finds next to nothing for ORB (the packaged file's textured walls give it 50
    keyframes at this seed) and the camera cannot decide; never a wrong claim."""
    import re

    world = str(files("symloc") / "data" / "worlds" / "square_with_box.yaml")
    args = ["demo", "--world", world, "--untextured", "--seed", "2", "--out", str(tmp_path)]
    assert main(args) == 0
    out = capsys.readouterr().out
    found = re.search(r"mapping trip: (\d+) keyframes of", out)
    assert found is not None
    assert int(found.group(1)) < 10
    assert re.search(r"^symloc: verdict\s+(\w[\w ]*)", out, re.M) is not None
    assert re.search(r"^symloc: verdict\s+confident wrong", out, re.M) is None
