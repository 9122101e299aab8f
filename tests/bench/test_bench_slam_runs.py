"""SLAM run inputs (symloc.bench.slam_runs): the log's own odometry, usable durations."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from symloc.bench.slam_runs import carmen_odometry, log_duration, log_odometry
from symloc.errors import ConfigurationError
from symloc.io.carmen import read_carmen


def _line(laser: tuple[float, float, float], odom: tuple[float, float, float], t: float) -> str:
    r = " ".join(["2.0"] * 4)
    return f"FLASER 4 {r} {laser[0]} {laser[1]} {laser[2]} {odom[0]} {odom[1]} {odom[2]} {t} h {t}"


def _write(path: Path, lines: list[str]) -> Path:
    path.write_text("\n".join(lines) + "\n")
    return path


def test_log_odometry_adds_the_laser_offset_and_refuses_corrected_logs(tmp_path: Path) -> None:
    raw = _write(
        tmp_path / "raw.log",
        [
            "PARAM robot_frontlaser_offset 0.1 nohost 0",
            _line((0.1, 0.0, 0.0), (0.0, 0.0, 0.0), 1.0),
            _line((0.0, 0.6, 1.5708), (0.0, 0.5, 1.5708), 2.0),
        ],
    )
    odo = log_odometry(read_carmen(raw))
    np.testing.assert_allclose(odo, [[0.1, 0.0, 0.0], [0.0, 0.6, 1.5708]], atol=1e-4)
    corrected = _write(
        tmp_path / "corrected.log",
        [_line((0.1, 0.0, 0.0), (0.1, 0.0, 0.0), 1.0), _line((0.2, 0, 0), (0.2, 0, 0), 2.0)],
    )
    with pytest.raises(ConfigurationError, match="carries no real odometry"):
        carmen_odometry(read_carmen(corrected), "log", 0, name="corrected")
    with pytest.raises(ConfigurationError, match="odometry: expected one of"):
        carmen_odometry(read_carmen(corrected), "perfect", 0)
    a = carmen_odometry(read_carmen(corrected), "realistic", 3)
    np.testing.assert_array_equal(a, carmen_odometry(read_carmen(corrected), "realistic", 3))


def test_log_duration_needs_increasing_stamps() -> None:
    assert log_duration(np.array([1.0, 2.0, 4.5])) == pytest.approx(3.5)
    assert log_duration(np.zeros(5)) is None  # orebro
    assert log_duration(np.array([1.13486e9] * 9 + [1.13487e9])) is None  # csail, truncated
    assert log_duration(np.array([3.0])) is None
