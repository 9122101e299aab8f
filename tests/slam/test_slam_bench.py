"""``symloc bench slam`` and its parts: measured processes, the peer log, targets, the CLI."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import make_scan
from symloc.bench.measure import run_measured
from symloc.bench.peers import GMappingPeer, PeerUnavailableError, write_peer_log
from symloc.bench.slam_bench import check_targets
from symloc.cli.main import main
from symloc.errors import ConfigurationError
from symloc.io.carmen import read_carmen


def test_run_measured_reports_the_childs_own_peak_memory() -> None:
    ballast = np.ones(30_000_000)  # 240 MB in this process must not show in the child's figure
    small = run_measured([sys.executable, "-S", "-c", "pass"])
    big = run_measured(
        [sys.executable, "-c", "import numpy as np; a = np.ones(20_000_000); print(a.size)"]
    )
    assert ballast.sum() > 0
    assert small.returncode == 0
    assert small.peak_rss_mb < 60
    assert big.stdout.strip() == "20000000"
    assert 150 < big.peak_rss_mb < 400  # 160 MB of ones plus the interpreter
    assert big.cpu_s > 0
    slow = run_measured([sys.executable, "-S", "-c", "import time; time.sleep(5)"], timeout=0.3)
    assert slow.timed_out
    assert slow.returncode == -9
    with pytest.raises(ConfigurationError, match="cannot run"):
        run_measured(["/nonexistent/slam-peer"])


def _loop(n: int) -> np.ndarray:
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    return np.column_stack([4.3 + 2.0 * np.cos(t), 3.0 + 1.1 * np.sin(t), t + math.pi / 2])


def test_peer_log_round_trips_through_the_reader(tmp_path: Path, room: np.ndarray) -> None:
    poses = _loop(12)
    scans = [make_scan(room, p) for p in poses]
    odo = poses + 0.01
    log = read_carmen(write_peer_log(tmp_path / "p.log", scans, odo, np.arange(12.0)))
    np.testing.assert_allclose(log.laser_poses, odo, atol=1e-6)
    np.testing.assert_allclose(log.odom_poses, odo, atol=1e-6)
    r0 = np.where(np.isfinite(scans[0].ranges), scans[0].ranges, scans[0].range_max)
    np.testing.assert_allclose(log.scans[0].scan.ranges, r0, atol=1e-4)
    assert log.scans[0].scan.angle_increment == pytest.approx(math.pi / 180)  # 181 beams


def test_peer_build_names_what_is_missing(tmp_path: Path) -> None:
    with pytest.raises(PeerUnavailableError, match="expected an openslam_gmapping checkout"):
        GMappingPeer.build(tmp_path)


def test_targets_realistic_and_heavy() -> None:
    def row(log: str, seed: int, a: float, mx: float, peer: float | None, mb: float) -> dict:
        systems = {"symloc": {"ate_rmse_m": a, "ate_max_m": mx, "peak_rss_mb": mb}}
        if peer is not None:
            systems["gmapping"] = {"ate_rmse_m": peer}
        return {"log": log, "seed": seed, "systems": systems, "duration_s": None}

    rows = [row("a", 0, 0.04, 0.1, 0.2, 200), row("b", 0, 0.09, 0.3, 0.10, 200)]
    pairs = [
        {
            "log": r["log"],
            "seed": r["seed"],
            "symloc_ate_m": r["systems"]["symloc"]["ate_rmse_m"],
            "symloc_max_m": r["systems"]["symloc"]["ate_max_m"],
            "best_peer_ate_m": r["systems"].get("gmapping", {}).get("ate_rmse_m"),
        }
        for r in rows
    ]
    t = check_targets(rows, pairs, "realistic")
    assert t["pairs_failed"] == []  # b: 0.09 m but below GMapping's 0.10 m
    assert not t["median_ok"]  # median 0.065 m
    assert not t["all_ok"]
    h = check_targets(rows, pairs, "heavy")
    assert h["pairs_failed"] == []
    assert h["all_ok"]
    rows[1]["systems"]["symloc"]["peak_rss_mb"] = 400
    pairs[1]["symloc_max_m"] = 0.7
    h = check_targets(rows, pairs, "heavy")
    assert h["pairs_failed"] == ["b/0"]
    assert h["logs_over_memory"] == ["b"]


def test_bench_slam_cli_runs_a_small_log_and_skips_a_peer_without_source(
    tmp_path: Path, room: np.ndarray, capsys: pytest.CaptureFixture[str]
) -> None:
    truth = np.vstack([_loop(40), _loop(40)[:8]])
    rng = np.random.default_rng(0)
    scans = [make_scan(room, p, rng) for p in truth]
    write_peer_log(tmp_path / "room-corrected.log", scans, truth, np.arange(truth.shape[0]) * 0.5)
    code = main(
        [
            "bench",
            "slam",
            "--carmen",
            str(tmp_path),
            "--seeds",
            "3",
            "--peers",
            "gmapping",
            "--workers",
            "1",
            "--out",
            str(tmp_path / "out"),
            "--odometry",
            "heavy",
        ]
    )
    out = capsys.readouterr().out
    assert code == 0
    assert "gmapping: skipped (no --peer-src" in out
    assert "room" in out
    assert "targets (heavy)" in out
    assert (tmp_path / "out" / "slam_bench_heavy.json").is_file()
    assert (tmp_path / "out" / "slam_bench_heavy.png").is_file()
    code = main(
        [
            "bench",
            "slam",
            "--carmen",
            str(tmp_path),
            "--odometry",
            "log",
            "--out",
            str(tmp_path / "o2"),
        ]
    )
    assert code == 0
    assert "carries no real odometry" in capsys.readouterr().out


def test_every_command_draws_the_same_odometry_for_a_log_and_seed(
    tmp_path: Path, room: np.ndarray
) -> None:
    """``map build`` and ``experiment slam`` (through ``run_carmen``) draw a log's noisy
    odometry from the stream ``bench slam`` draws it from; other logs draw other streams."""
    from symloc.bench.slam_runs import carmen_odometry, log_name, odometry_seed, run_carmen

    poses = _loop(12)
    scans = [make_scan(room, p) for p in poses]
    path = write_peer_log(tmp_path / "lab-corrected.log", scans, poses, np.arange(12.0))
    assert log_name(path) == "lab"
    run = run_carmen(path, odometry="realistic", rng=7, progress=False)
    bench = carmen_odometry(
        read_carmen(path), "realistic", np.random.default_rng(odometry_seed("lab", 7)), name="lab"
    )
    np.testing.assert_array_equal(run.odometry, bench)
    other = carmen_odometry(
        read_carmen(path), "realistic", np.random.default_rng(odometry_seed("aces", 7)), name="lab"
    )
    assert not np.allclose(other, bench)
    again = run_carmen(path, odometry="realistic", rng=8, progress=False)
    assert not np.allclose(again.odometry, bench)
