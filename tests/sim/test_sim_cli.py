"""``symloc sim render`` end to end (small, one run)."""

from __future__ import annotations

from pathlib import Path

import cv2
import pytest

from symloc.cli.main import main


def test_sim_render_writes_scene_and_image(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "scene.png"
    cam = tmp_path / "cam.png"
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
            "--image-out",
            str(cam),
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "seed=3" in text
    assert "room=hexagon" in text
    assert "360 beams" in text
    assert out.stat().st_size > 10_000
    img = cv2.imread(str(cam))
    assert img.shape == (480, 640, 3)


def test_sim_render_bad_gv_is_a_clean_error(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    code = main(["sim", "render", "--gv", "0", "--out", str(tmp_path / "x.png")])
    assert code == 2
    assert "gv: expected a value > 0" in capsys.readouterr().err


def _packaged(name: str) -> Path:
    from importlib import resources

    return Path(str(resources.files("symloc") / "data" / "worlds" / name))


def test_sim_render_world_file(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "scene.png"
    code = main(
        ["sim", "render", "--world", str(_packaged("square_with_box.yaml")), "--out", str(out)]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "room=square-with-box" in text
    assert "order=1 shape_order=4" in text
    assert out.stat().st_size > 10_000


def test_sim_render_world_file_errors_name_the_key(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nroom:\n  polygon: [[0, 0], [2, 2], [2, 0], [0, 2]]\n")
    code = main(["sim", "render", "--world", str(bad), "--out", str(tmp_path / "x.png")])
    assert code == 2
    err = capsys.readouterr().err
    assert f"{bad}: room.polygon[0]: wall 0" in err
    assert "crosses wall 2" in err


def test_sim_world_writes_a_loadable_file(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from symloc.sim.generator import generate_world
    from symloc.sim.world_file import load_world_file

    out = tmp_path / "w.yaml"
    assert (
        main(
            [
                "sim",
                "world",
                "--family",
                "rhombus",
                "--seed",
                "7",
                "--no-perturb",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "family=rhombus seed=7" in text
    assert "computed: order 2" in text
    assert out.read_text().startswith("# symloc sim world --family rhombus --seed 7 --no-perturb\n")
    assert load_world_file(out) == generate_world("rhombus", 7, perturb=False)
    assert main(["sim", "world", "--room", "hexagon", "--gv", "2.5", "--no-lab"]) == 0
    text = capsys.readouterr().out
    assert "computed: order 6" in text
    assert "regular: {n: 6, gv: 2.5}" in text
    assert main(["sim", "world", "--list"]) == 0
    assert "corridor_long   symmetric" in capsys.readouterr().out
    assert main(["sim", "world"]) == 2


def test_sim_gallery(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    code = main(
        ["sim", "gallery", "--out", str(tmp_path), "--count", "2", "--families", "kite", "cross"]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "kite-0" in text
    assert "cross-1" in text
    assert (tmp_path / "worlds_gallery.png").stat().st_size > 5_000
