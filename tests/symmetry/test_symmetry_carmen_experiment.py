"""``symloc experiment symmetry-carmen`` and the partial-view judgement of front scans."""

from __future__ import annotations

import gzip
import json
import math
from pathlib import Path

import numpy as np
import pytest

from symloc.bench.shared_data import carmen_log_file, find_carmen_dir
from symloc.cli.main import main
from symloc.errors import ConfigurationError
from symloc.experiments.symmetry_carmen import reason_tag, run_symmetry_carmen
from symloc.scan import LaserScan
from symloc.symmetry import SymmetryConfig, judge_symmetry, scan_lines
from symloc.symmetry.order import SymmetryOrder


def _front_scan(ranges: np.ndarray) -> LaserScan:
    return LaserScan(-math.pi / 2, math.pi / ranges.size, 0.0, 50.0, ranges)


def _hallway(n: int = 180, left: float = 1.0, right: float = 1.2, tilt: float = 0.0) -> np.ndarray:
    """Front scan along a hallway (walls at y = left and y = -right, rotated by ``tilt``)."""
    a = -math.pi / 2 + math.pi * np.arange(n) / n + tilt
    s = np.sin(a)
    with np.errstate(divide="ignore"):
        r = np.where(s > 0, left / s, right / -s)
    r[~np.isfinite(r) | (r > 45.0)] = 81.91
    return r


def _dead_end(n: int = 180) -> np.ndarray:
    """Front scan of a corridor whose end wall is 6 m ahead."""
    r = _hallway(n)
    a = -math.pi / 2 + math.pi * np.arange(n) / n
    c = np.cos(a)
    with np.errstate(divide="ignore"):
        end = np.where(c > 0, 6.0 / c, np.inf)
    return np.asarray(np.minimum(r, end), dtype=np.float64)


def test_partial_view_hallway_only_when_asked() -> None:
    scan = _front_scan(_hallway(tilt=math.radians(8.0)))
    strict = judge_symmetry(scan)
    assert strict.kind == "unknown"
    assert "field of view 180 deg" in strict.reason
    rep = judge_symmetry(scan, config=SymmetryConfig(partial_view=True))
    assert rep.kind == "hallway"
    assert rep.symmetric
    assert rep.order == SymmetryOrder.finite(2)
    assert "assumed to continue" in rep.reason
    # the centre lies on the mid-line, 0.1 m to the right of the sensor across the hallway
    # (walls 1.0 m left and 1.2 m right), whatever the heading
    assert abs(float(np.hypot(*rep.center)) - 0.1) < 0.02


def test_partial_view_does_not_claim_a_dead_end_or_a_room() -> None:
    cfg = SymmetryConfig(partial_view=True)
    rep = judge_symmetry(_front_scan(_dead_end()), config=cfg)
    assert not rep.symmetric
    assert rep.kind == "unknown"
    a = -math.pi / 2 + math.pi * np.arange(180) / 180
    room = 2.0 / np.maximum(np.abs(np.cos(a)), np.abs(np.sin(a)))  # front half of a square
    rep = judge_symmetry(_front_scan(room), config=cfg)
    assert not rep.symmetric


def test_partial_view_config_validation() -> None:
    with pytest.raises(ConfigurationError, match="partial_view: expected a bool"):
        SymmetryConfig(partial_view="yes")  # type: ignore[arg-type]


def test_scan_lines_of_a_hallway() -> None:
    lines = scan_lines(_front_scan(_hallway()))
    assert lines.runs.shape == (2, 2)
    walls = lines.n_points >= 3
    assert int(walls.sum()) == 2
    # both walls horizontal (along x)
    d = lines.segments[walls, 1] - lines.segments[walls, 0]
    assert np.all(np.abs(d[:, 1]) < 0.02 * np.abs(d[:, 0]))
    empty = scan_lines(_front_scan(np.full(180, 81.91)))
    assert empty.segments.shape == (0, 2, 2)
    with pytest.raises(ConfigurationError, match="scan: expected a LaserScan"):
        scan_lines(np.ones(5))  # type: ignore[arg-type]


def test_reason_tags() -> None:
    assert reason_tag("field of view 180 deg < 360 deg: ...") == "field of view < 360 deg"
    assert reason_tag("an opening 0.80 m wide ...") == "opening in a straight wall (door)"
    assert reason_tag("something new") == "other"


def _write_log(path: Path, scans: list[np.ndarray]) -> None:
    rows = []
    for i, r in enumerate(scans):
        vals = " ".join(f"{v:.3f}" for v in r)
        rows.append(f"FLASER {r.size} {vals} 0 0 0 0 0 0 {i:.1f} host {i:.1f}")
    with gzip.open(path, "wt") as fh:
        fh.write("\n".join(rows) + "\n")


def test_experiment_on_a_synthetic_log(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = tmp_path / "carmen"
    data.mkdir()
    _write_log(data / "aces-corrected.log.gz", [_hallway(), _dead_end(), _hallway(tilt=0.1)])
    js = tmp_path / "r.json"
    code = main(
        [
            "experiment", "symmetry-carmen", "--data", str(data), "--logs", "aces",
            "--seed", "1", "--out", str(tmp_path), "--json", str(js),
        ]
    )  # fmt: skip
    assert code == 0
    out = capsys.readouterr().out
    assert "seed: 1" in out
    res = json.loads(js.read_text())
    aces = res["logs"]["aces"]
    assert aces["strict"] == {"unknown": 3}
    assert aces["strict_symmetric"] == 0
    assert aces["partial"] == {"hallway": 2, "unknown": 1}
    assert aces["symmetric_indices"] == [0, 2]
    assert (tmp_path / "symmetry_carmen_symmetric.png").stat().st_size > 1000
    assert (tmp_path / "symmetry_carmen_sample.png").stat().st_size > 1000


def test_experiment_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(ConfigurationError, match="stride: expected an integer >= 1"):
        run_symmetry_carmen(tmp_path, ["aces"], stride=0)
    with pytest.raises(ConfigurationError, match="logs: expected names from"):
        run_symmetry_carmen(tmp_path, ["mit"])
    code = main(["experiment", "symmetry-carmen", "--data", str(tmp_path / "none")])
    assert code == 2
    err = capsys.readouterr().err
    assert (
        f"symloc: error: --data {tmp_path / 'none'}: the CARMEN logs' folder was not found" in err
    )


CARMEN = find_carmen_dir()  # $SYMLOC_SHARED_DATA/carmen or ../shared/data/carmen
HAS_INTEL = CARMEN is not None and carmen_log_file(CARMEN, "intel").is_file()


@pytest.mark.skipif(
    not HAS_INTEL,
    reason="shared CARMEN data not found (../shared/data/carmen or $SYMLOC_SHARED_DATA)",
)
def test_real_intel_log_every_20th_scan_never_claims_symmetry_strictly() -> None:
    res = run_symmetry_carmen(CARMEN, ["intel"], stride=20, progress=False)
    intel = res["logs"]["intel"]
    assert intel["n_judged"] == 46
    # 180-degree scans: the strict judgement must not claim anything
    assert intel["strict"] == {"unknown": 46}
    assert sum(intel["partial"].values()) == 46


def test_corridor_like_diagnostic() -> None:
    from symloc.experiments.symmetry_carmen import corridor_like

    assert corridor_like(scan_lines(_front_scan(_hallway(tilt=0.05))))
    a = -math.pi / 2 + math.pi * np.arange(180) / 180
    room = 2.0 / np.maximum(np.abs(np.cos(a)), np.abs(np.sin(a)))  # front half of a square
    assert not corridor_like(scan_lines(_front_scan(room)))
    # one long wall only (the robot faces along a wall, open space on the other side)
    one = _hallway()
    one[: one.size // 2] = 81.91
    assert not corridor_like(scan_lines(_front_scan(one)))


def test_narrow_no_return_gap_in_a_wall_is_a_dropout_not_a_door() -> None:
    # full scan from the centre of a 4 m square, a few no-return beams in the wall at x = 2
    n = 720
    a = -math.pi + 2 * math.pi * np.arange(n) / n
    r = 2.0 / np.maximum(np.abs(np.cos(a)), np.abs(np.sin(a)))
    scan = LaserScan(-math.pi, 2 * math.pi / n, 0.1, 12.0, r)
    k = int(np.argmin(np.abs(a)))  # bearing 0: the wall at x = 2 m, beams 1 cm apart there
    narrow = r.copy()
    narrow[k : k + 6] = np.inf  # ~0.1 m: a dark patch, not a door
    rep = judge_symmetry(scan.with_ranges(narrow))
    assert rep.kind == "unknown"
    assert "sensor dropouts, not doors" in rep.reason
    wide = r.copy()
    wide[k - 12 : k + 12] = np.inf  # ~0.42 m: still under min_door_width = 0.5 m
    assert "opening" not in judge_symmetry(scan.with_ranges(wide)).reason
    door = r.copy()
    door[k - 12 : k + 12] = np.inf
    rep = judge_symmetry(scan.with_ranges(door), config=SymmetryConfig(min_door_width=0.3))
    assert rep.kind == "asymmetric"
    assert "an opening 0.4" in rep.reason


def test_min_door_width_validation() -> None:
    with pytest.raises(ConfigurationError, match="min_door_width: expected < max_door_width"):
        SymmetryConfig(min_door_width=2.5)
