"""``symloc vocab``: train from a folder, convert DBoW2 text <-> native, info; error paths."""

from __future__ import annotations

from pathlib import Path

import cv2
import pytest
import skimage.data

from symloc.cli.main import main
from symloc.vision.vocabulary import Vocabulary


def _folder(tmp_path: Path) -> Path:
    d = tmp_path / "train"
    (d / "sub").mkdir(parents=True)
    for name in ("camera", "brick"):
        cv2.imwrite(str(d / f"{name}.png"), getattr(skimage.data, name)())
    cv2.imwrite(str(d / "sub" / "coins.jpg"), skimage.data.coins())  # type: ignore[no-untyped-call]
    return d


def test_train_info_convert_round_trip(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = _folder(tmp_path)
    (folder / "notes.png").write_text("not an image")  # skipped with a warning
    args = ["vocab", "train", str(folder), "--k", "4", "--L", "2", "--out", str(tmp_path / "v1")]
    assert main([*args, "--seed", "3", "--weighting", "tf", "--scoring", "l2"]) == 0
    captured = capsys.readouterr()
    assert "skipped 1 unreadable" in captured.err
    out = tmp_path / "v1" / "vocabulary.symvoc"  # --out is a folder
    voc = Vocabulary.load(out)
    assert (voc.k, voc.L, voc.weighting.name, voc.scoring.name) == (4, 2, "TF", "L2_NORM")
    # same seed, same vocabulary (here as DBoW2 text)
    v2 = tmp_path / "v2"
    argv = [*args[:-1], str(v2), "--seed", "3", "--weighting", "tf", "--scoring", "l2"]
    assert main([*argv, "--format", "dbow2"]) == 0
    assert Vocabulary.load(v2 / "vocabulary.txt").equals(voc, weight_rtol=1e-12)

    assert main(["vocab", "info", str(out)]) == 0
    info = capsys.readouterr().out
    for expected in ("k:         4", f"words:     {voc.n_words}", "TF", "L2_NORM", "symloc binary"):
        assert expected in info

    txt = tmp_path / "voc.txt"
    assert main(["vocab", "convert", str(out), str(txt)]) == 0
    assert txt.read_text().splitlines()[0].split() == ["4", "2", "1", "1"]
    back = tmp_path / "back.symvoc"
    assert main(["vocab", "convert", str(back), str(back)]) == 2  # never writes its input
    assert "never writes into its input" in capsys.readouterr().err
    assert main(["vocab", "convert", str(txt), str(back), "--compress"]) == 0
    assert Vocabulary.load(back).equals(voc, weight_rtol=1e-12)
    capsys.readouterr()
    assert main(["vocab", "info", str(back)]) == 0
    assert "(compressed)" in capsys.readouterr().out
    assert main(["vocab", "info", str(txt)]) == 0
    assert "DBoW2 text" in capsys.readouterr().out


def test_train_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = str(tmp_path / "v")
    assert main(["vocab", "train", str(tmp_path / "missing"), "--out", out]) == 2
    assert "is not a directory" in capsys.readouterr().err
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["vocab", "train", str(empty), "--out", out]) == 2
    assert "no images" in capsys.readouterr().err
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "a.png").write_bytes(b"\x89PNG garbage")
    (bad / "b.jpg").write_text("nope")
    assert main(["vocab", "train", str(bad), "--out", out]) == 2
    assert "none of the 2 image file(s)" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["vocab", "train", str(bad), "--k", "0"])
    assert "--k: expected an integer >= 1, got 0" in capsys.readouterr().err


def test_corrupt_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = _folder(tmp_path)
    assert (
        main(["vocab", "train", str(folder), "--k", "3", "--L", "2", "--out", str(tmp_path)]) == 0
    )
    out = tmp_path / "vocabulary.symvoc"
    capsys.readouterr()
    trunc = tmp_path / "trunc.symvoc"
    trunc.write_bytes(out.read_bytes()[:200])
    assert main(["vocab", "info", str(trunc)]) == 2
    assert "truncated" in capsys.readouterr().err
    junk = tmp_path / "junk.bin"
    junk.write_bytes(b"hello world")
    assert main(["vocab", "convert", str(junk), str(tmp_path / "x.symvoc")]) == 2
    assert "not a symloc vocabulary" in capsys.readouterr().err
    txt = tmp_path / "voc.txt"
    assert main(["vocab", "convert", str(out), str(txt)]) == 0
    lines = txt.read_text().splitlines()
    lines[3] = lines[3].replace(" ", " x", 1)
    txt.write_text("\n".join(lines) + "\n")
    capsys.readouterr()
    assert main(["vocab", "info", str(txt)]) == 2
    assert "line 4" in capsys.readouterr().err
    assert main(["vocab", "info", str(tmp_path / "missing.symvoc")]) == 2
    assert "cannot read" in capsys.readouterr().err
