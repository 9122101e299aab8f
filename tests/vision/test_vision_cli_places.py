"""``symloc places``: add / list / decide / remove on users' photo files; error paths."""

from __future__ import annotations

import math
import sqlite3
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np
import pytest

from symloc.bench.photos import PLACE_PHOTOS, load_scene, view
from symloc.cli.main import main
from symloc.errors import ConfigurationError, DataFormatError
from symloc.vision.image_files import intrinsics_from_fov, intrinsics_from_values, read_image


@lru_cache(maxsize=1)
def _scenes() -> tuple[np.ndarray, ...]:
    return tuple(load_scene(n) for n in PLACE_PHOTOS)


def _write(path: Path, rgb: np.ndarray) -> Path:
    cv2.imwrite(str(path), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    return path


def _setup(tmp_path: Path) -> tuple[Path, list[str]]:
    imgs = [str(_write(tmp_path / f"d{j + 1}.png", view(s))) for j, s in enumerate(_scenes())]
    db = tmp_path / "places.db"
    args = ["places", "add", "--db", str(db), "--images", *imgs, "--kind", "polygon"]
    assert main([*args, "--order", "4", "--gv", "2.12", "--pose", "1", "2", "90"]) == 0
    return db, imgs


def test_add_list_decide_remove(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    db, _ = _setup(tmp_path)
    out = capsys.readouterr().out
    assert "added place 1" in out
    assert main(["places", "list", "--db", str(db)]) == 0
    out = capsys.readouterr().out
    assert "1 place(s)" in out
    assert "polygon" in out
    assert "2.120" in out
    # a JPEG re-capture of the third photo (direction 3 for people) after the camera turned
    # 3 degrees left
    q = _write(tmp_path / "q.jpg", view(_scenes()[2], math.radians(3.0)))
    assert main(["places", "decide", "--db", str(db), "--place", "1", "--query", str(q),
                 "--hfov", f"{math.degrees(2 * math.atan(320 / 500)):.4f}"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "status:         decided" in out
    assert "direction:      3 of 4" in out
    offset = float(out.split("heading offset:")[1].split("deg")[0])
    assert abs(offset - 3.0) < 0.5
    # direction 3 looks along 90 - 2 x 90 = -90 deg; the camera turned 3 deg left
    heading = float(out.split("heading:")[1].split("deg")[0])
    assert abs(heading - (-87.0)) < 0.5
    # same with explicit intrinsics
    assert main(["places", "decide", "--db", str(db), "--place", "1", "--query", str(q),
                 "--intrinsics", "500", "500", "320", "240"]) == 0  # fmt: skip
    assert "direction:      3 of 4" in capsys.readouterr().out
    # a flat wall is refused (exit code 3) and the user is told to turn
    flat = tmp_path / "flat.png"
    cv2.imwrite(str(flat), np.full((480, 640), 128, np.uint8))
    assert main(["places", "decide", "--db", str(db), "--place", "1", "--query", str(flat),
                 "--hfov", "65"]) == 3  # fmt: skip
    out = capsys.readouterr().out
    assert "status:         refused" in out
    assert "turn clockwise by 90 deg" in out
    assert main(["places", "remove", "--db", str(db), "--place", "1"]) == 0
    assert "0 left" in capsys.readouterr().out


def test_place_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    db, imgs = _setup(tmp_path)
    capsys.readouterr()
    q = imgs[0]
    assert main(["places", "decide", "--db", str(db), "--place", "9", "--query", q,
                 "--hfov", "60"]) == 2  # fmt: skip
    assert "no place with id 9" in capsys.readouterr().err
    assert main(["places", "remove", "--db", str(db), "--place", "9"]) == 2
    assert "no place with id 9" in capsys.readouterr().err
    notes = tmp_path / "notes.png"
    notes.write_text("not an image")
    add = ["places", "add", "--db", str(db), "--order", "2", "--gv", "1"]
    assert main([*add, "--images", imgs[0], str(notes)]) == 2
    assert "notes.png: not a readable image" in capsys.readouterr().err
    assert main([*add, "--images", imgs[0], str(tmp_path / "missing.png")]) == 2
    assert "no such image file" in capsys.readouterr().err
    assert main([*add, "--images", *imgs[:3]]) == 2
    assert "multiple of the order" in capsys.readouterr().err
    assert main(["places", "decide", "--db", str(db), "--place", "1", "--query", str(notes),
                 "--hfov", "60"]) == 2  # fmt: skip
    assert "not a readable image" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:  # a usage error since --hfov has its bound
        main(["places", "decide", "--db", str(db), "--place", "1", "--query", q,
              "--hfov", "190"])  # fmt: skip
    assert exc.value.code == 2
    assert "argument --hfov: expected at most 179" in capsys.readouterr().err
    # not a symloc database: a text file, and another application's SQLite file
    fake = tmp_path / "fake.db"
    fake.write_text("hello")
    assert main(["places", "list", "--db", str(fake)]) == 2
    assert "not a symloc visual map" in capsys.readouterr().err
    other = tmp_path / "other.db"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE t (x)")
    con.commit()
    con.close()
    assert main(["places", "list", "--db", str(other)]) == 2
    assert "not a symloc visual map" in capsys.readouterr().err
    assert main(["places", "list", "--db", str(tmp_path / "none.db")]) == 2
    assert "no visual map there" in capsys.readouterr().err
    # a map made with one vocabulary refuses places described with another
    train = tmp_path / "train"
    train.mkdir()
    for i in range(2):
        _write(train / f"{i}.png", view(_scenes()[i]))
    assert main(["vocab", "train", str(train), "--k", "3", "--L", "2", "--out", str(tmp_path)]) == 0
    voc = tmp_path / "vocabulary.symvoc"
    capsys.readouterr()
    assert main([*add, "--images", *imgs[:2], "--vocabulary", str(voc)]) == 2
    assert "were made with the shipped vocabulary" in capsys.readouterr().err


def test_image_file_helpers(tmp_path: Path) -> None:
    grey = tmp_path / "g.png"
    cv2.imwrite(str(grey), np.arange(64 * 48, dtype=np.uint16).reshape(48, 64))
    img = read_image(grey)
    assert img.dtype == np.uint8
    assert img.shape == (48, 64)
    assert img.max() == 255
    rgba = tmp_path / "c.png"
    bgra = np.zeros((4, 5, 4), np.uint8)
    bgra[..., 0] = 255  # blue
    cv2.imwrite(str(rgba), bgra)
    assert read_image(rgba)[0, 0].tolist() == [0, 0, 255]
    K = intrinsics_from_fov(90.0, 640, 480)
    assert K[0, 0] == pytest.approx(320.0)
    assert K[1, 2] == pytest.approx(240.0)
    with pytest.raises(ConfigurationError, match=r"hfov: expected a value in \(0, 180\)"):
        intrinsics_from_fov(0.0, 640, 480)
    with pytest.raises(ConfigurationError, match="image size"):
        intrinsics_from_fov(60.0, 0, 480)
    with pytest.raises(ConfigurationError, match="fx, fy > 0"):
        intrinsics_from_values(-1.0, 500.0, 320.0, 240.0)
    with pytest.raises(DataFormatError, match="no such image file"):
        read_image(tmp_path / "nope.png")


def test_decide_refuses_another_vocabulary_and_stored_paths(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db, imgs = _setup(tmp_path)  # made with the shipped vocabulary
    train = tmp_path / "train"
    train.mkdir()
    for i in range(2):
        _write(train / f"{i}.png", view(_scenes()[i]))
    assert main(["vocab", "train", str(train), "--k", "3", "--L", "2", "--out", str(tmp_path)]) == 0
    voc = tmp_path / "vocabulary.symvoc"
    capsys.readouterr()
    decide = ["places", "decide", "--db", str(db), "--place", "1", "--query", imgs[0]]
    assert main([*decide, "--hfov", "60", "--vocabulary", str(voc)]) == 2
    assert "were made with the shipped vocabulary, not" in capsys.readouterr().err
    # a crafted database naming a file as its vocabulary: the path is never opened
    con = sqlite3.connect(db)
    con.execute("UPDATE meta SET value = '/etc/passwd' WHERE key = 'vocabulary'")
    con.commit()
    con.close()
    assert main([*decide, "--hfov", "60"]) == 2
    assert "never opens a path stored in the database" in capsys.readouterr().err
    assert main([*decide, "--hfov", "60", "--vocabulary", str(voc)]) == 2
    assert "were made with /etc/passwd, not" in capsys.readouterr().err


def test_photos_too_small_for_orb_are_clean_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 1 x 1 photo crashed places add and places decide in OpenCV (issue 31)."""
    db, imgs = _setup(tmp_path)
    capsys.readouterr()
    tiny = tmp_path / "tiny.png"
    cv2.imwrite(str(tiny), np.full((1, 1), 128, np.uint8))
    add = ["places", "add", "--db", str(db), "--order", "2", "--gv", "1"]
    assert main([*add, "--images", imgs[0], str(tiny)]) == 2
    assert "tiny.png: 1 x 1 pixels; a photo needs at least 63 x 63" in capsys.readouterr().err
    assert main(["places", "decide", "--db", str(db), "--place", "1", "--query", str(tiny),
                 "--hfov", "60"]) == 2  # fmt: skip
    assert "tiny.png: 1 x 1 pixels" in capsys.readouterr().err
