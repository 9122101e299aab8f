"""The shared option definitions of symloc.cli.options: validation, units, numbering, JSON."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pytest

from symloc.cli import options
from symloc.symmetry.order import SymmetryOrder


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="t")
    options.add_seed(p)
    options.add_out(p, "experiment table1")
    options.add_json(p)
    options.add_lidars(p)
    options.add_room(p)
    options.add_trials(p, default=7, what="trials per room")
    options.add_angle(p, "--yaw", default=90.0, help="camera yaw")
    return p


def test_defaults_and_units() -> None:
    args = _parser().parse_args([])
    assert args.seed == 0
    assert args.out == Path("symloc-experiment-table1")
    assert args.json is None
    assert options.lidar_names(args.lidar) == ["rplidar_a2"]
    assert args.room == "square"
    assert args.trials == 7
    assert args.yaw == pytest.approx(math.pi / 2)  # degrees in, radians out
    args = _parser().parse_args(["--lidar", "all", "lds01", "--yaw", "-45"])
    assert options.lidar_names(args.lidar) == ["lds01", "paper_15m", "rplidar_a2"]
    assert args.yaw == pytest.approx(-math.pi / 4)
    assert "[degrees, default 90 deg]" in _parser().format_help()


@pytest.mark.parametrize(
    "argv",
    [
        ["--seed", "-1"],
        ["--seed", "1.5"],
        ["--trials", "0"],
        ["--trials", "-5"],
        ["--lidar", "sick"],
        ["--room", "attic"],
        ["--yaw", "nan"],
    ],
)
def test_bad_values_are_usage_errors(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        _parser().parse_args(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "expected" in err or "invalid choice" in err
    assert "Traceback" not in err


def test_people_numbering() -> None:
    assert options.direction_text(0, 4) == "1 of 4"
    assert options.direction_text(3) == "4"
    assert options.order_text(SymmetryOrder.CIRCLE) == "inf"
    assert options.order_text(SymmetryOrder.finite(4)) == "4"
    assert options.order_text(None) == "-"


def test_json_is_standard(tmp_path: Path) -> None:
    data = {
        "a": float("nan"),
        "b": np.float32(1.5),
        "c": np.array([1.0, np.inf]),
        "d": (np.int64(3), Path("x")),
        "e": np.bool_(True),
    }
    path = options.write_json(tmp_path / "sub" / "r.json", data)
    text = path.read_text()
    assert "NaN" not in text
    assert "Infinity" not in text
    assert json.loads(text) == {"a": None, "b": 1.5, "c": [1.0, None], "d": [3, "x"], "e": True}


# ----------------------------------------------------------------------- output paths


def test_output_problem_names_what_is_wrong(tmp_path: Path) -> None:
    f = tmp_path / "f"
    f.write_text("x")
    d = tmp_path / "d"
    d.mkdir()
    assert options.output_problem(d, folder=True) is None
    assert options.output_problem(d / "new" / "deeper", folder=True) is None
    assert options.output_problem(f, folder=False) is None
    assert options.output_problem(d / "new" / "r.json", folder=False) is None
    assert "is an existing file; expected a folder" in str(options.output_problem(f, folder=True))
    assert "is an existing folder; expected a file" in str(options.output_problem(d, folder=False))
    assert f"{f} is a file, not a folder" in str(
        options.output_problem(f / "x" / "y", folder=False)
    )
    assert "character device" in str(options.output_problem("/dev/null", folder=False))
    assert "character device" in str(options.output_problem("/dev/null", folder=True))
    assert "empty path" in str(options.output_problem("", folder=True))
    assert "NUL" in str(options.output_problem("a\x00b", folder=False))
    assert "longer than 255 bytes" in str(options.output_problem(d / ("n" * 300), folder=True))
    assert "names a folder" in str(options.output_problem(str(d) + "/", folder=False))


def test_output_problem_refuses_unwritable_folders(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Permissions as os.access reports them (root passes every permission bit, so the test
    stands in for a user whose folder is read-only)."""
    import os

    locked = tmp_path / "locked"
    locked.mkdir()
    (locked / "old.json").write_text("{}")
    real = os.access
    monkeypatch.setattr(os, "access", lambda p, m: real(p, m) and Path(p) != locked)
    assert "not writable" in str(options.output_problem(locked / "sub", folder=True))
    assert "cannot write into" in str(options.output_problem(locked, folder=True))
    assert "not writable" in str(options.output_problem(locked / "old.json", folder=False))
    assert options.output_problem(tmp_path / "free", folder=True) is None


def test_output_types_are_usage_errors(tmp_path: Path) -> None:
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(argparse.ArgumentTypeError, match=f"{f} is an existing file"):
        options.output_folder(str(f))
    with pytest.raises(argparse.ArgumentTypeError, match=f"{tmp_path} is an existing folder"):
        options.output_file(str(tmp_path))
    assert options.output_file(str(tmp_path / "r.json")) == tmp_path / "r.json"
    with pytest.raises(argparse.ArgumentTypeError, match="plain file name"):
        options.file_stem("../map")
    assert options.file_stem("map") == "map"


# ----------------------------------------------------------------------- numeric bounds


@pytest.mark.parametrize(
    ("kind", "text", "message"),
    [
        (options.particles, "1000000000", "at most 4,000,000 (about 240 B per particle"),
        (options.gv_distance, "1e9", "at most 100 m (the room and its lab are rasterised"),
        (options.map_resolution, "1e-6", "at least 0.01 m (1 cm cells"),
        (options.gallery_count, "100000000", "at most 256 (every world is a panel"),
        (options.count, "99999999999", "at most 10,000 (each keeps its record"),
        (options.vocabulary_levels, "11", "at most 10 (DBoW2's deepest tree)"),
        (options.sim_seconds, "1e9", "at most 3,600 s (the run keeps every scan"),
    ],
)
def test_numeric_options_have_upper_bounds_with_their_reason(
    kind: object, text: str, message: str
) -> None:
    with pytest.raises(argparse.ArgumentTypeError) as exc:
        kind(text)  # type: ignore[operator]
    assert message in str(exc.value)
    assert str(exc.value).endswith(f"got {text}")


def test_bounds_keep_the_values_people_use() -> None:
    assert options.particles("20000") == 20000
    assert options.gv_distance("3") == 3.0
    assert options.map_resolution("0.05") == 0.05
    assert options.gallery_count("16") == 16
    with pytest.raises(argparse.ArgumentTypeError, match="expected an integer >= 1"):
        options.count("0")
