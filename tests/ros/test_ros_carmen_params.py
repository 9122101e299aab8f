"""``carmen-to-bag --odom-alpha`` writes the odometry ``symloc experiment amcl-carmen`` tracks
with (issue 28: replay within 0.02 m of the experiment's tracking error)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from symloc.cli.main import main
from symloc.errors import ConfigurationError
from symloc.experiments.amcl_carmen import (
    tracking_odometry,
)
from symloc.geometry import wrap_angle
from symloc.io.carmen import read_carmen
from symloc.io.rosbag import read_bag
from symloc.io.rosbag_carmen import carmen_to_bag


def _carmen(path: Path, scans: int = 12) -> Path:
    """A small corrected CARMEN log: the robot drives 0.3 m and turns 0.1 rad per scan."""
    lines = []
    for i in range(scans):
        ranges = " ".join(f"{2.0 + 0.001 * j:.3f}" for j in range(180))
        pose = f"{0.3 * i:.2f} {0.05 * i:.2f} {0.1 * i:.2f}"
        lines.append(f"FLASER 180 {ranges} {pose} {pose} {1.0 + i} host {1.0 + i}")
    path.write_text("\n".join(lines) + "\n")
    return path


def _odometry(bag: Path) -> np.ndarray:
    return np.array([m.value.pose for m in read_bag(bag) if m.kind == "odom"])


def test_carmen_to_bag_writes_the_experiments_odometry(tmp_path: Path) -> None:
    log = _carmen(tmp_path / "tiny-corrected.log")
    truth = read_carmen(log).laser_poses.copy()
    truth[:, 2] = wrap_angle(truth[:, 2])
    assert main(["ros", "carmen-to-bag", str(log), "--out", str(tmp_path / "own")]) == 0
    np.testing.assert_allclose(_odometry(tmp_path / "own" / "tiny-corrected"), truth, atol=1e-9)
    argv = ["ros", "carmen-to-bag", str(log), "--odom-alpha", "0.01", "--seed", "3"]
    assert main([*argv, "--out", str(tmp_path / "noisy")]) == 0
    odom = _odometry(tmp_path / "noisy" / "tiny-corrected")
    want = tracking_odometry("tiny", truth, 0.01, 3)
    np.testing.assert_allclose(odom[:, :2], want[:, :2], atol=1e-9)
    np.testing.assert_allclose(wrap_angle(odom[:, 2] - want[:, 2]), 0.0, atol=1e-9)
    assert np.abs(odom[1:, :2] - truth[1:, :2]).max() > 1e-4  # noisy, not the log's own


def test_carmen_to_bag_refuses_odometry_of_another_length(tmp_path: Path) -> None:
    log = _carmen(tmp_path / "tiny-corrected.log")
    with pytest.raises(
        ConfigurationError, match=r"odometry: expected 12 finite poses .* \(11, 3\)"
    ):
        carmen_to_bag(log, tmp_path / "bag", odometry=np.zeros((11, 3)))
    assert not (tmp_path / "bag").exists()
