"""``symloc symmetry judge``: scans from a simulated room, a CARMEN log and a ROS bag."""

from __future__ import annotations

import gzip
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from symloc.bench.scan_sources import bag_scan, carmen_scan, room_scan
from symloc.cli.main import main
from symloc.errors import ConfigurationError, DataFormatError
from symloc.scan import LaserScan


def _square_ranges(n: int, half: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Ranges of a full scan from the centre of a square of half-side ``half`` (axis-aligned)."""
    a = -math.pi + 2 * math.pi * np.arange(n) / n
    r = half / np.maximum(np.abs(np.cos(a)), np.abs(np.sin(a)))
    return a, r


def _write_carmen(path: Path, scans: list[np.ndarray], fov: float = math.pi) -> None:
    lines = ["# synthetic", "PARAM robot_front_laser_max 50.0"]
    for i, r in enumerate(scans):
        vals = " ".join(f"{v:.3f}" for v in r)
        lines.append(
            f"FLASER {r.size} {vals} {i * 0.1:.3f} 0 0 {i * 0.1:.3f} 0 0 {1.0 + i:.3f} host"
            f" {1.0 + i:.3f}"
        )
    text = "\n".join(lines) + "\n"
    with gzip.open(path, "wt") as fh:
        fh.write(text)


def _hallway_front_ranges(n: int = 180, half_width: float = 1.0) -> np.ndarray:
    """A 180-degree front scan looking along a hallway of half-width 1 m (far end unseen)."""
    a = -math.pi / 2 + math.pi * np.arange(n) / n
    with np.errstate(divide="ignore"):
        r = half_width / np.abs(np.sin(a))
    r[r > 40.0] = 81.91  # the SICK "no return" marker
    return r


def test_room_square_prints_report_truth_png_and_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    png, js = tmp_path / "j.png", tmp_path / "j.json"
    argv = ["symmetry", "judge", "--room", "square", "--gv", "3", "--pose", "0.5", "-0.7", "30"]
    code = main([*argv, "--png", str(png), "--json", str(js)])
    out = capsys.readouterr().out
    assert code == 0
    assert "kind        polygon" in out
    assert "order       4" in out
    assert "truth       polygon, order 4" in out
    assert png.stat().st_size > 1000
    data = json.loads(js.read_text())
    assert data["report"]["order"] == 4
    # the centre the judge reports matches the room's true centre in the sensor frame
    np.testing.assert_allclose(data["report"]["center"], data["truth"]["center"], atol=0.05)


def test_room_scan_truth_is_in_the_sensor_frame() -> None:
    src = room_scan("hexagon", 5.0, [1.0, -1.0, 90.0], rng=1)
    # room centre at the origin; robot at (1, -1) facing +y: centre is 1 m ahead, 1 m right...
    np.testing.assert_allclose(src.truth["center"], [1.0, 1.0], atol=1e-9)
    assert src.truth["order"] == 6
    assert src.sigma == pytest.approx(0.01)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"room": "dodecahedron"}, "room: expected one of"),
        ({"gv": -1.0}, "gv: expected a G-V distance > 0"),
        ({"pose": [0.0, 0.0]}, "pose: expected three finite numbers"),
        ({"pose": [9.0, 0.0, 0.0]}, "pose: .* is outside the square"),
        ({"sensor": "velodyne"}, "sensor: expected one of"),
    ],
)
def test_room_scan_errors(kwargs: dict[str, Any], match: str) -> None:
    args: dict[str, Any] = {"room": "square", "gv": 3.0, "pose": [0.0, 0.0, 0.0]} | kwargs
    with pytest.raises(ConfigurationError, match=match):
        room_scan(args.pop("room"), args.pop("gv"), args.pop("pose"), **args)


def test_carmen_front_scan_unknown_by_default_hallway_with_partial_view(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "hall.log.gz"
    _write_carmen(log, [_hallway_front_ranges(), _hallway_front_ranges()])
    assert main(["symmetry", "judge", "--carmen", str(log), "--index", "1"]) == 0
    out = capsys.readouterr().out
    assert "kind        unknown" in out
    assert "field of view 180 deg" in out
    assert main(["symmetry", "judge", "--carmen", str(log), "--partial-view"]) == 0
    out = capsys.readouterr().out
    assert "kind        hallway" in out
    assert "assumed to continue" in out


def test_carmen_scan_errors(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match="log file not found"):
        carmen_scan(tmp_path / "missing.log")
    log = tmp_path / "one.log.gz"
    _write_carmen(log, [_hallway_front_ranges()])
    with pytest.raises(DataFormatError, match=r"index: expected -1 <= N < 1 .* got 3"):
        carmen_scan(log, 3)
    with pytest.raises(ConfigurationError, match="index: expected an integer"):
        carmen_scan(log, 1.5)  # type: ignore[arg-type]
    empty = tmp_path / "empty.log"
    empty.write_text("# nothing\n")
    with pytest.raises(DataFormatError, match="holds no FLASER scan"):
        carmen_scan(empty)
    assert carmen_scan(log, -1).index == 0


def test_bag_scan_and_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from symloc.io.rosbag import BagWriter

    path = tmp_path / "run"
    _a, r = _square_ranges(360)
    rng = np.random.default_rng(0)
    with BagWriter(path) as w:
        for i in range(3):
            ranges = r + rng.normal(0.0, 0.005, r.size)
            w.write_scan(LaserScan(-math.pi, 2 * math.pi / 360, 0.1, 12.0, ranges, stamp=1.0 + i))
    src = bag_scan(path, "/scan", 2)
    assert src.index == 2
    assert src.count == 3
    assert src.scan.stamp == pytest.approx(3.0)
    assert bag_scan(path).index == 0  # the first LaserScan topic by default
    assert main(["symmetry", "judge", "--bag", str(path), "--topic", "scan", "--index", "1"]) == 0
    out = capsys.readouterr().out
    assert "kind        polygon" in out
    assert "order       4" in out
    with pytest.raises(DataFormatError, match=r"index: expected 0 <= N < 3"):
        bag_scan(path, "/scan", 7)
    with pytest.raises(DataFormatError, match="bag topic '/nope' for scan not found"):
        bag_scan(path, "/nope", 0)
    with pytest.raises(ConfigurationError, match="index: expected >= 0"):
        bag_scan(path, "/scan", -1)
    with pytest.raises(DataFormatError, match="does not exist"):
        bag_scan(tmp_path / "nobag")


def test_bag_without_laser_scan_topic(tmp_path: Path) -> None:
    from symloc.io.rosbag import BagWriter
    from symloc.odometry import OdometryReading

    path = tmp_path / "odo"
    with BagWriter(path) as w:
        w.write_odometry(OdometryReading(np.zeros(3), 1.0))
    with pytest.raises(DataFormatError, match="no sensor_msgs/LaserScan topic"):
        bag_scan(path)


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--carmen", "x.log", "--gv", "3"], "--gv only apply to a simulated room"),
        (["--bag", "x", "--room", "circle"], "--room only apply to a simulated room"),
        (["--carmen", "x.log", "--topic", "/scan"], "--topic only applies to --bag"),
    ],
)
def test_cli_argument_errors(
    argv: list[str], match: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["symmetry", "judge", *argv]) == 2
    assert match in capsys.readouterr().err


def test_cli_library_errors_are_reported(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["symmetry", "judge", "--carmen", str(tmp_path / "none.log")])
    assert code == 2
    assert "log file not found" in capsys.readouterr().err
    code = main(["symmetry", "judge", "--room", "square", "--gv", "3", "--pose", "7", "0", "0"])
    assert code == 2
    assert "is outside the square" in capsys.readouterr().err


def test_cli_usage_errors(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["symmetry", "judge", "--carmen", "a.log", "--bag", "b"])
    assert "not allowed with argument" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["symmetry", "judge", "--furniture", "-1"])
    assert "--furniture: expected an integer >= 0, got -1" in capsys.readouterr().err


def test_cli_default_source_is_the_square(capsys: pytest.CaptureFixture[str]) -> None:
    """No source: the paper's 3 m x 3 m square, robot off-centre, the paper's lidar."""
    assert main(["symmetry", "judge"]) == 0
    out = capsys.readouterr().out
    assert "order       4" in out
    assert "800 beams" in out  # rplidar_a2, the one default lidar
