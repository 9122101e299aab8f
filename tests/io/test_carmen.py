"""Tests of the CARMEN log reader (symloc.io.carmen)."""

from __future__ import annotations

import gzip
import math
import os
from pathlib import Path

import numpy as np
import pytest

from symloc.errors import DataFormatError
from symloc.io.carmen import iter_carmen, read_carmen

SHARED = Path(
    os.environ.get(
        "SYMLOC_SHARED_DATA", Path(__file__).resolve().parents[2] / ".." / "shared" / "data"
    )
)


def _flaser(n: int = 4, t: float = 1.5, ranges: list[float] | None = None) -> str:
    r = ranges if ranges is not None else [1.0 + 0.5 * i for i in range(n)]
    vals = " ".join(str(v) for v in r)
    return f"FLASER {n} {vals} 1.0 2.0 0.5 1.1 2.1 0.6 {t} host {t + 0.01}"


LOG = "\n".join(
    [
        "# message formats defined: PARAM SYNC ODOM FLASER",
        "PARAM robot_frontlaser_offset 0.0 nohost 0",
        "ODOM 0.1 0.2 0.3 0.4 0.5 0.6 1.0 host 1.0",
        _flaser(t=1.5, ranges=[1.0, 81.91, 2.0, 3.0]),
        "NEFF 15",
        "",
        "TRUEPOS 1 2 3",
        _flaser(t=2.5),
    ]
)


def test_reads_scans_odometry_params_and_skipped(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    p.write_text(LOG + "\n")
    log = read_carmen(p)
    assert len(log.scans) == 2
    assert len(log.odometry) == 1
    s = log.scans[0]
    assert s.line == 4
    np.testing.assert_allclose(s.laser_pose, [1.0, 2.0, 0.5])
    np.testing.assert_allclose(s.odom_pose, [1.1, 2.1, 0.6])
    assert s.stamp == 1.5
    assert s.logger_stamp == pytest.approx(1.51)
    assert s.scan.angle_min == pytest.approx(-math.pi / 2)
    assert s.scan.angle_increment == pytest.approx(math.pi / 4)
    assert s.scan.no_return_mask.tolist() == [False, True, False, False]
    assert log.skipped == {"NEFF": 1, "TRUEPOS": 1}
    assert log.params == {"robot_frontlaser_offset": "0.0"}
    assert log.duration == pytest.approx(1.0)
    assert log.laser_poses.shape == (2, 3)
    assert log.stamps.tolist() == [1.5, 2.5]
    o = log.odometry[0]
    np.testing.assert_allclose(o.pose, [0.1, 0.2, 0.3])
    assert (o.tv, o.rv, o.accel, o.line) == (0.4, 0.5, 0.6, 3)


def test_gzip_gives_the_same_messages(tmp_path: Path) -> None:
    p = tmp_path / "a.log.gz"
    with gzip.open(p, "wt") as fh:
        fh.write(LOG)
    q = tmp_path / "a.log"
    q.write_text(LOG)
    a, b = read_carmen(p), read_carmen(q)
    np.testing.assert_array_equal(a.laser_poses, b.laser_poses)
    np.testing.assert_array_equal(a.scans[1].scan.ranges, b.scans[1].scan.ranges)


def test_iter_yields_in_file_order(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    p.write_text(LOG)
    kinds = [type(m).__name__ for m in iter_carmen(p)]
    assert kinds == ["CarmenOdometry", "CarmenScan", "CarmenScan"]


@pytest.mark.parametrize(
    ("line", "match"),
    [
        ("FLASER", "line 2: FLASER: missing the number"),
        ("FLASER x 1 2", "line 2: FLASER number of readings: expected an integer"),
        ("FLASER 1 1.0 0 0 0 0 0 0 1 h 1", "line 2: FLASER number of readings: expected >= 2"),
        ("FLASER 3 1 2 0 0 0 0 0 0 1 h 1", "line 2: FLASER with 3 readings: expected 14 fields"),
        (_flaser(ranges=[1, "a", 2, 3]), "line 2: FLASER ranges: expected numbers"),
        (_flaser(ranges=[1, -2, 2, 3]), "line 2: FLASER ranges: expected values >= 0"),
        (_flaser(ranges=[1, "nan", 2, 3]), "line 2: FLASER ranges: expected finite"),
        ("ODOM 1 2 3", "line 2: ODOM: expected 10 fields"),
        ("ODOM 1 2 x 0 0 0 1 h 1", "line 2: ODOM values: expected numbers"),
        ("PARAM onlyname", "line 2: PARAM: expected a name and a value"),
    ],
)
def test_malformed_lines_name_the_line(tmp_path: Path, line: str, match: str) -> None:
    p = tmp_path / "bad.log"
    p.write_text("# header\n" + line + "\n")
    with pytest.raises(DataFormatError, match=match):
        read_carmen(p)


def test_missing_file_and_bad_range_max(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match="CARMEN log not found"):
        read_carmen(tmp_path / "none.log")
    p = tmp_path / "a.log"
    p.write_text(LOG)
    with pytest.raises(DataFormatError, match="range_max: expected > 0"):
        read_carmen(p, range_max=0.0)


@pytest.mark.skipif(
    not (SHARED / "carmen" / "aces-corrected.log.gz").is_file(),
    reason="shared CARMEN data not present (../shared/data/carmen or SYMLOC_SHARED_DATA)",
)
def test_real_aces_log_counts() -> None:
    log = read_carmen(SHARED / "carmen" / "aces-corrected.log.gz")
    assert len(log.scans) == 440
    assert log.skipped["NEFF"] == 440
    assert all(len(s.scan) == 180 for s in log.scans)
    assert log.duration > 1000.0


def test_truncated_gzip_and_long_lines_name_the_file(tmp_path: Path) -> None:
    import gzip

    import symloc.io.carmen as carmen

    gz = tmp_path / "cut.log.gz"
    whole = gzip.compress(LOG.encode() * 50)
    gz.write_bytes(whole[: len(whole) // 2])
    with pytest.raises(DataFormatError, match=r"cut\.log\.gz: line \d+: cannot read on"):
        read_carmen(gz)
    bad = tmp_path / "bad.log"
    bad.write_text("# header\nODOM 1 2\n")
    with pytest.raises(DataFormatError, match=r"bad\.log: line 2: ODOM"):
        read_carmen(bad)
    long = tmp_path / "long.log"
    long.write_text("FLASER " + "1 " * (carmen.MAX_LINE // 2 + 10) + "\n")
    with pytest.raises(DataFormatError, match=r"long\.log: line 1: longer than"):
        read_carmen(long)
