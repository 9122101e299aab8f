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
