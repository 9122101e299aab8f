"""``symloc sim render`` end to end (small, one run)."""

from __future__ import annotations

from pathlib import Path

import cv2
import pytest

from symloc.cli.main import main


def test_sim_render_writes_scene_and_image(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "render"
    code = main(
        [
            "sim",
            "render",
            "--room",
            "hexagon",
            "--gv",
            "3",
            "--door",
            "--furniture",
            "1",
            "--lidar",
            "lds01",
            "--seed",
            "3",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "seed=3" in text
    assert "room=hexagon" in text
    assert "360 beams" in text
    assert (out / "scene.png").stat().st_size > 10_000
    img = cv2.imread(str(out / "camera.png"))
    assert img.shape == (480, 640, 3)


def test_sim_render_bad_gv_is_a_clean_error(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["sim", "render", "--gv", "0", "--out", str(tmp_path / "x")])
    assert exc.value.code == 2
    assert "--gv: expected a number > 0, got '0'" in capsys.readouterr().err
