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


def _log_with(n: int, params: list[str]) -> str:
    return "\n".join([*params, _flaser(n=n, ranges=[1.0] * n)]) + "\n"


@pytest.mark.parametrize(
    ("n", "params", "step_deg"),
    [
        (180, [], 1.0),  # a 181-beam sweep with the last beam dropped: pi / n
        (181, [], 1.0),  # both ends of the sweep: pi / (n - 1)
        (360, [], 0.5),
        (361, [], 0.5),
        (360, ["PARAM laser_front_laser_resolution 0.5 x 0"], 0.5),
        (180, ["PARAM laser_frontlaser_resolution 1 0.0 nohost 0"], 1.0),  # the fhw spelling
        (361, ["PARAM laser_front_laser_fov 3.14159 1 b21 1"], 0.5),  # radians (csail)
        (101, ["PARAM laser_front_laser_fov 100 1 h 1"], 1.0),  # degrees, CARMEN's ini unit
    ],
)
def test_beam_geometry_from_beam_count_and_params(
    tmp_path: Path, n: int, params: list[str], step_deg: float
) -> None:
    p = tmp_path / "g.log"
    p.write_text(_log_with(n, params))
    scan = read_carmen(p).scans[0].scan
    assert math.degrees(scan.angle_increment) == pytest.approx(step_deg, abs=1e-4)
    fov = math.radians(100.0) if n == 101 else math.pi
    assert scan.angle_min == pytest.approx(-fov / 2, abs=1e-5)
    # 180 / 360 beams stop one step short of +90 deg; 181 / 361 reach it
    last = scan.angle_min + (n - 1) * scan.angle_increment
    assert last == pytest.approx(fov / 2 if n % 2 else fov / 2 - scan.angle_increment, abs=1e-5)


def test_bad_geometry_params_name_the_line(tmp_path: Path) -> None:
    p = tmp_path / "g.log"
    p.write_text(_log_with(4, ["PARAM laser_front_laser_resolution fine x 0"]))
    with pytest.raises(DataFormatError, match="line 1: PARAM laser_front_laser_resolution"):
        read_carmen(p)
    p.write_text(_log_with(800, ["PARAM laser_front_laser_resolution 1 x 0"]))
    with pytest.raises(DataFormatError, match="line 2: FLASER with 800 readings at 1 deg"):
        read_carmen(p)


@pytest.mark.skipif(
    not (SHARED / "carmen" / "orebro-corrected.log.gz").is_file(),
    reason="shared CARMEN data not present (../shared/data/carmen or SYMLOC_SHARED_DATA)",
)
def test_real_181_beam_scans_fit_each_other_best_with_the_read_geometry() -> None:
    """orebro (181 beams): scans at the corrected poses agree better with pi/(n-1) than pi/n."""
    from scipy.spatial import cKDTree

    log = read_carmen(SHARED / "carmen" / "orebro-corrected.log.gz")
    scans = log.scans[::2]
    n = len(scans[0].scan)

    def spread(step: float) -> float:
        halves: list[list[np.ndarray]] = [[], []]
        for k, s in enumerate(scans):
            r = s.scan.ranges
            ok = (r > 0.05) & (r < 15.0)
            a = s.laser_pose[2] + s.scan.angle_min + step * np.arange(n)[ok]
            halves[k % 2].append(
                s.laser_pose[:2] + r[ok, None] * np.column_stack([np.cos(a), np.sin(a)])
            )
        a, b = (np.vstack(h) for h in halves)
        d, _ = cKDTree(b).query(a, distance_upper_bound=0.3)
        return float(np.minimum(d, 0.3).mean())

    assert scans[0].scan.angle_increment == pytest.approx(math.pi / (n - 1))
    assert spread(math.pi / (n - 1)) < spread(math.pi / n) - 0.001


def test_a_gz_of_blank_lines_is_refused_at_once(tmp_path: Path) -> None:
    """A 200 KB .gz that expands to 200 MiB of newlines (issue 31: 82-92 s before its error)
    is refused after MAX_LINES_WITHOUT_DATA lines, naming them."""
    import time

    from symloc.io.carmen import MAX_LINES_WITHOUT_DATA

    path = tmp_path / "blank.log.gz"
    with gzip.open(path, "wb", compresslevel=9) as fh:
        fh.write(b"FLASER 3 1 2 3 0 0 0 0 0 0 1 h 1\n")
        for _ in range(200):
            fh.write(b"\n" * (1 << 20))
    assert path.stat().st_size < 300_000
    t0 = time.perf_counter()
    with pytest.raises(DataFormatError) as exc:
        read_carmen(path)
    assert time.perf_counter() - t0 < 5.0
    text = str(exc.value)
    assert str(path) in text
    assert f"lines 2-{MAX_LINES_WITHOUT_DATA + 2}: " in text
    assert "blank or comment lines in a row" in text


def test_line_numbers_count_the_blank_lines(tmp_path: Path) -> None:
    path = tmp_path / "gaps.log"
    path.write_text("# header\n\n\n   \nODOM 1 2\n")
    with pytest.raises(DataFormatError, match="line 5: ODOM: expected 10 fields"):
        read_carmen(path)
