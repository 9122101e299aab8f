"""NodeCore: pairing scans with odometry and images, outputs, and surviving bad input."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from symloc.grid import OccupancyGrid
from symloc.localizer import Estimate, Hypothesis, Request, RequestKind, Status
from symloc.msgs import (
    build_rosbags,
    grid_to_fields,
    image_to_fields,
    odometry_to_fields,
    pose_with_covariance_to_fields,
    scan_to_fields,
)
from symloc.odometry import OdometryReading
from symloc.ros.core import NodeCore
from symloc.ros.params import NodeParams
from symloc.scan import LaserScan
from symloc.symmetry.order import SymmetryOrder

TS = get_typestore(Stores.ROS2_HUMBLE)


class ScriptedLocalizer:
    """Returns scripted estimates; records what it was given."""

    def __init__(self, script: list[Estimate]) -> None:
        self.script = list(script)
        self.calls: list[tuple[OdometryReading, LaserScan, object]] = []
        self.poses_set: list[np.ndarray] = []
        self.last_result = None
        self.forced = 0

    def force_update(self) -> None:
        self.forced += 1

    def update(self, odom, scan, image=None):  # type: ignore[no-untyped-def]
        self.calls.append((odom, scan, image))
        i = min(len(self.calls) - 1, len(self.script) - 1)
        return self.script[i]

    def set_pose(self, pose, cov):  # type: ignore[no-untyped-def]
        self.poses_set.append(np.asarray(pose))


LOST = Estimate(Status.LOST, reason="not converged")
TRACK = Estimate(
    Status.TRACKING,
    pose=np.array([1.0, 2.0, 0.5]),
    covariance=np.diag([0.01, 0.01, 0.001]),
    hypotheses=(Hypothesis(np.array([1.0, 2.0, 0.5]), 1.0),),
    reason="tracking",
)


def _ambiguous(req: Request) -> Estimate:
    hyps = tuple(Hypothesis(np.array([0.0, 0.0, a]), 0.25) for a in (0, 1.57, 3.14, -1.57))
    return Estimate(
        Status.AMBIGUOUS,
        hypotheses=hyps,
        order=SymmetryOrder.finite(4),
        request=req,
        reason="symmetric",
    )


def _core(
    script: list[Estimate], **params: object
) -> tuple[NodeCore, ScriptedLocalizer, list[str]]:
    loc = ScriptedLocalizer(script)
    warnings: list[str] = []
    core = NodeCore(NodeParams(**params), factory=lambda g, p: loc, warn=warnings.append)  # type: ignore[arg-type]
    return core, loc, warnings


def _msg(msgtype: str, fields: dict) -> object:
    return build_rosbags(TS, msgtype, fields)


def _map_msg(shape: tuple[int, int] = (20, 20), frame: str = "map") -> object:
    grid = OccupancyGrid(np.zeros(shape, np.int8), 0.05)
    return _msg("nav_msgs/msg/OccupancyGrid", grid_to_fields(grid, stamp=0.0, frame_id=frame))


def _odom_msg(
    t: float, pose=(0.0, 0.0, 0.0), frame: str = "odom", child: str = "base_link"
) -> object:
    f = odometry_to_fields(
        OdometryReading(np.asarray(pose, float), t), frame_id=frame, child_frame_id=child
    )
    return _msg("nav_msgs/msg/Odometry", f)


def _scan_msg(t: float, n: int = 36, frame: str = "laser") -> object:
    scan = LaserScan(-math.pi, 2 * math.pi / n, 0.1, 8.0, np.full(n, 2.0), stamp=t, frame_id=frame)
    return _msg("sensor_msgs/msg/LaserScan", scan_to_fields(scan))


def test_scans_need_a_map_and_odometry() -> None:
    core, _loc, warns = _core([LOST])
    assert not core.on_scan(_scan_msg(1.0)).used
    assert core.dropped["scan: no map yet"] == 1
    core.on_map(_map_msg())
    assert not core.on_scan(_scan_msg(1.0)).used
    assert core.dropped["scan: no odometry yet"] == 1
    core.on_odom(_odom_msg(1.0))
    out = core.on_scan(_scan_msg(1.0))
    assert out is not None
    assert out.amcl_pose is None  # lost: no pose published
    assert out.status["status"][0]["level"] == 2
    assert any("no map yet" in w for w in warns)


def test_odometry_is_interpolated_at_the_scan_stamp() -> None:
    core, loc, _ = _core([LOST])
    core.on_map(_map_msg())
    core.on_odom(_odom_msg(1.0, (0.0, 0.0, 3.0)))
    core.on_odom(_odom_msg(2.0, (1.0, 2.0, -3.0)))
    core.on_scan(_scan_msg(1.5))
    odom = loc.calls[-1][0]
    np.testing.assert_allclose(odom.pose[:2], [0.5, 1.0])
    # heading interpolated the short way across +-pi
    assert abs(abs(odom.pose[2]) - math.pi) < 0.3
    core.on_scan(_scan_msg(2.0))
    np.testing.assert_array_equal(loc.calls[-1][0].pose, [1.0, 2.0, wrap(-3.0)])
    assert not core.on_scan(_scan_msg(5.0)).used  # > transform_tolerance after the newest
    assert core.dropped["scan: no odometry within transform_tolerance"] == 1


def wrap(a: float) -> float:
    return math.remainder(a, 2 * math.pi)


def test_tracking_publishes_amcl_pose_and_status_values() -> None:
    core, _, _ = _core([TRACK])
    core.on_map(_map_msg())
    core.on_odom(_odom_msg(1.0))
    out = core.on_scan(_scan_msg(1.0))
    assert out is not None
    assert out.amcl_pose is not None
    assert out.amcl_pose["header"]["frame_id"] == "map"
    values = {kv["key"]: kv["value"] for kv in out.status["status"][0]["values"]}
    assert values["status"] == "tracking"
    assert values["pose"].split()[0] == "1"
    # the dicts build real messages
    _msg("geometry_msgs/msg/PoseWithCovarianceStamped", out.amcl_pose)
    _msg("diagnostic_msgs/msg/DiagnosticArray", out.status)
    _msg("visualization_msgs/msg/MarkerArray", out.candidates)


def test_requests_become_goal_and_capture_and_image_is_paired() -> None:
    script = [
        _ambiguous(Request(RequestKind.GO_TO_CENTRE, target=np.array([1.0, 1.0]))),
        # the localizer asks until it gets an image
        _ambiguous(Request(RequestKind.CAPTURE_IMAGE)),
        _ambiguous(Request(RequestKind.CAPTURE_IMAGE)),
        _ambiguous(Request(RequestKind.CAPTURE_IMAGE)),
        _ambiguous(Request(RequestKind.ROTATE, angle=-math.pi / 2)),
    ]
    core, loc, _ = _core(script)
    core.on_map(_map_msg())
    core.on_odom(_odom_msg(1.0, (2.0, 0.0, math.pi / 2)))
    out = core.on_scan(_scan_msg(1.0))
    assert out is not None
    assert out.goal is not None
    g = out.goal["pose"]["position"]
    assert out.goal["header"]["frame_id"] == "odom"
    np.testing.assert_allclose([g["x"], g["y"]], [1.0, 1.0], atol=1e-12)  # base (1,1) in odom
    values = {kv["key"]: kv["value"] for kv in out.status["status"][0]["values"]}
    assert values["request"] == "go_to_centre"
    assert values["candidate_3"].split()[-1] == "0.25"
    assert len(out.candidates["markers"]) == 1 + 4 + 1
    out = core.on_scan(_scan_msg(1.0))
    assert out is not None
    assert out.capture is not None
    img = np.zeros((4, 5, 3), np.uint8)
    core.on_image(_msg("sensor_msgs/msg/Image", image_to_fields(img, stamp=0.5)))  # too old
    core.on_odom(_odom_msg(1.2, (2.0, 0.0, math.pi / 2)))
    core.on_scan(_scan_msg(1.1))
    assert loc.calls[-1][2] is None
    core.on_image(_msg("sensor_msgs/msg/Image", image_to_fields(img + 7, stamp=1.05)))
    core.on_scan(_scan_msg(1.2))
    assert loc.calls[-1][2] is not None
    assert int(loc.calls[-1][2][0, 0, 0]) == 7
    core.on_scan(_scan_msg(1.2))
    assert loc.calls[-1][2] is None  # an image is given once


def test_bad_input_is_dropped_counted_and_survived() -> None:
    capture = Estimate(
        Status.TRACKING,
        pose=TRACK.pose,
        covariance=TRACK.covariance,
        request=Request(RequestKind.CAPTURE_IMAGE),
        reason="capture",
    )
    core, loc, warns = _core([capture, TRACK], laser_frame_id="laser", camera_frame_id="camera")
    core.on_map(_map_msg())
    core.on_odom(_odom_msg(1.0))
    assert core.on_scan(_scan_msg(1.0)).used  # asks for an image: images are decoded now
    # wrong length, wrong frame
    assert not core.on_scan(_scan_msg(1.0, n=35)).used
    assert not core.on_scan(_scan_msg(1.0, frame="base_link")).used
    # NaN odometry, wrong odom frames, stamps going backwards
    nan_odom = odometry_to_fields(OdometryReading(np.zeros(3), 1.1))
    nan_odom["pose"]["pose"]["position"]["y"] = float("nan")
    core.on_odom(_msg("nav_msgs/msg/Odometry", nan_odom))
    core.on_odom(_odom_msg(1.2, frame="map"))
    core.on_odom(_odom_msg(1.2, child="laser"))
    core.on_odom(_odom_msg(0.5))
    # unknown image encoding, wrong camera frame
    bad_img = image_to_fields(np.zeros((2, 2, 3), np.uint8), stamp=1.0)
    bad_img["encoding"] = "yuv422"
    core.on_image(_msg("sensor_msgs/msg/Image", bad_img))
    core.on_image(
        _msg(
            "sensor_msgs/msg/Image",
            image_to_fields(np.zeros((2, 2, 3), np.uint8), stamp=1.0, frame_id="x"),
        )
    )
    # NaN initial pose, wrong frame
    nan_pose = pose_with_covariance_to_fields([np.nan, 0, 0], np.eye(3), stamp=1.0)
    core.on_initialpose(_msg("geometry_msgs/msg/PoseWithCovarianceStamped", nan_pose))
    core.on_initialpose(
        _msg(
            "geometry_msgs/msg/PoseWithCovarianceStamped",
            pose_with_covariance_to_fields([0, 0, 0], np.eye(3), stamp=1.0, frame_id="odom"),
        )
    )
    # a map in the wrong frame
    core.on_map(_map_msg(frame="odom"))
    # a scan with no valid reading
    core.on_scan(
        _msg(
            "sensor_msgs/msg/LaserScan",
            scan_to_fields(
                LaserScan(
                    -math.pi,
                    2 * math.pi / 36,
                    0.1,
                    8.0,
                    np.full(36, np.nan),
                    stamp=1.0,
                    frame_id="laser",
                )
            ),
        )
    )
    # malformed scan
    bad_scan = scan_to_fields(
        LaserScan(0.0, 0.1, 0.1, 5.0, np.ones(36), stamp=1.0, frame_id="laser")
    )
    bad_scan["angle_increment"] = float("nan")
    core.on_scan(_msg("sensor_msgs/msg/LaserScan", bad_scan))
    expected = {
        "scan: wrong length": 1,
        "scan: wrong frame": 1,
        "odom: malformed": 1,
        "odom: wrong frame": 1,
        "odom: wrong child frame": 1,
        "odom: stamp went backwards": 1,
        "image: malformed": 1,
        "image: wrong frame": 1,
        "initialpose: malformed": 1,
        "initialpose: wrong frame": 1,
        "map: wrong frame": 1,
        "scan: malformed": 1,
        "scan: no valid readings": 1,
    }
    assert dict(core.dropped) == expected
    assert loc.poses_set == []
    assert any("yuv422" in w for w in warns)
    assert any("Odometry.pose.pose.position.y" in w for w in warns)
    # still localizing
    out = core.on_scan(_scan_msg(1.0))
    assert out is not None
    assert out.amcl_pose is not None
    values = {kv["key"]: kv["value"] for kv in out.status["status"][0]["values"]}
    assert values["dropped"] == str(len(expected))
    assert values["dropped/map: wrong frame"] == "1"


def test_every_new_map_rebuilds_and_keeps_the_pose() -> None:
    built: list[OccupancyGrid] = []
    loc = ScriptedLocalizer([TRACK])

    def factory(grid, params):  # type: ignore[no-untyped-def]
        built.append(grid)
        return loc

    core = NodeCore(NodeParams(), factory=factory)  # nav2: every map unless first_map_only
    core.on_map(_map_msg())
    core.on_map(_map_msg())  # identical re-publication: ignored
    core.on_odom(_odom_msg(1.0))
    core.on_scan(_scan_msg(1.0))
    core.on_map(_map_msg((60, 40)))  # 2 m x 3 m: the tracked pose (1, 2) is inside
    assert len(built) == 2
    assert loc.poses_set == []  # seeded at the next scan, carried to its odometry
    core.on_odom(_odom_msg(1.2))
    core.on_scan(_scan_msg(1.2))
    np.testing.assert_allclose(loc.poses_set[-1], [1.0, 2.0, 0.5])
    only = NodeCore(NodeParams(first_map_only=True), factory=factory)
    only.on_map(_map_msg())
    assert not only.set_map(OccupancyGrid(np.zeros((5, 5), np.int8), 0.1))
    assert len(built) == 3


def test_a_map_file_s_own_error_reaches_the_claim_gate() -> None:
    """A map whose file declares its error (``symloc_slam.map_error``) raises the claim gate's
    map error to it; the next map, from the topic, declares none and the default is back."""
    stds: list[float] = []

    def factory(grid, params):  # type: ignore[no-untyped-def]
        stds.append(params.claim.map_std_xy)
        return ScriptedLocalizer([TRACK])

    core = NodeCore(NodeParams(), factory=factory)
    grid = OccupancyGrid(np.zeros((20, 20), np.int8), 0.1)
    assert core.set_map(grid, map_std_xy=0.07)
    assert core.set_map(OccupancyGrid(np.zeros((30, 20), np.int8), 0.1))
    assert core.set_map(OccupancyGrid(np.zeros((30, 30), np.int8), 0.1), map_std_xy=0.001)
    default = NodeParams().claim.map_std_xy
    assert stds == [pytest.approx(0.07), pytest.approx(default), pytest.approx(default)]


def test_a_maps_error_field_reaches_the_claim_gate() -> None:
    """The field a map file declares (``symloc_slam.map_error.field``) is given to the claim
    gate of the localizer built on it, and to no other map's."""
    from symloc.grid.map_error_field import MapErrorField
    from symloc.localizer.build import build_localizer
    from symloc.localizer.settings import LocalizerSettings

    def factory(grid, params):  # type: ignore[no-untyped-def]
        return build_localizer(grid, dataclasses.replace(LocalizerSettings(), claim=params.claim))

    data = np.zeros((40, 40), np.int8)
    data[[0, -1], :] = 100
    data[:, [0, -1]] = 100
    field = MapErrorField(np.array([[1.0, 1.0]]), np.eye(2)[None] * 0.05**2)
    core = NodeCore(NodeParams(), factory=factory)
    assert core.set_map(OccupancyGrid(data, 0.1), map_error_field=field)
    assert core.localizer is not None
    assert core.localizer.claim_gate is not None
    assert core.localizer.claim_gate.map_error_field is field
    assert core.set_map(OccupancyGrid(data[:, :30].copy(), 0.1))
    assert core.localizer.claim_gate is not None
    assert core.localizer.claim_gate.map_error_field is None


def test_warnings_are_rate_limited() -> None:
    core, _, warns = _core([LOST])
    for _ in range(250):
        core.on_scan(_scan_msg(1.0))
    assert core.dropped["scan: no map yet"] == 250
    assert len(warns) == 5 + 2  # the first five, then the 100th and the 200th


@pytest.mark.parametrize("mode", ["localise", ""])
def test_params_reject_bad_mode(mode: str) -> None:
    from symloc.errors import ConfigurationError

    with pytest.raises(ConfigurationError, match="mode: expected one of"):
        NodeParams(mode=mode)


def test_example_params_file_is_valid() -> None:
    from pathlib import Path

    import symloc.ros

    path = Path(symloc.ros.__file__).parent / "examples" / "symloc_params.yaml"
    params = NodeParams.from_yaml(path)
    assert params.lidar_preset == "lds01"
    assert params.amcl.max_particles == 2000
    assert params.camera_intrinsics == (503.0, 503.0, 320.0, 240.0)
    assert params.symmetry_config().range_sigma > 0


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("other:\n  ros__parameters: {}\n", r"no block for node 'symloc'"),
        ("symloc:\n  ros__parameters:\n    bogus: 1\n", r"parameter 'bogus': unknown"),
        ("symloc:\n  ros__parameters:\n    amcl: {alpha9: 1}\n", r"alpha9"),
        ("symloc:\n  ros__parameters:\n    localizer: {nope: 1}\n", r"localizer\.nope"),
        ("symloc:\n  ros__parameters:\n    symmetry: {nope: 1}\n", r"symmetry\.nope"),
        ("symloc:\n  ros__parameters:\n    camera_intrinsics: [1, 2]\n", r"camera_intrinsics"),
        ("symloc:\n  ros__parameters:\n    lidar_preset: sick\n", r"lidar_preset"),
        ("symloc:\n  ros__parameters:\n    sensor_qos: fast\n", r"sensor_qos"),
        ("symloc:\n  ros__parameters:\n    transform_tolerance: -1\n", r"transform_tolerance"),
        ("symloc:\n  ros__parameters:\n    scan_topic: 'a b'\n", r"scan_topic"),
        ("symloc:\n  ros__parameters:\n    odom_frame_id: ''\n", r"odom_frame_id"),
        ("symloc:\n  ros__parameters:\n    seed: -3\n", r"seed"),
        ("symloc:\n  ros__parameters:\n    max_stamp_jump: 0\n", r"max_stamp_jump"),
        ("symloc:\n  ros__parameters:\n    max_odom_speed: .nan\n", r"max_odom_speed.*m/s"),
        ("symloc:\n  ros__parameters:\n    max_image_pixels: 0\n", r"max_image_pixels"),
        ("symloc: [1, 2\n", r"not valid YAML"),
        ("symloc: 3\n", r"ros__parameters block"),
    ],
)
def test_params_errors_name_the_parameter(text: str, match: str) -> None:
    from symloc.errors import ConfigurationError

    with pytest.raises(ConfigurationError, match=match):
        NodeParams.from_yaml(text)


def test_params_namespaced_and_wildcard_blocks() -> None:
    p = NodeParams.from_yaml("robot1/symloc:\n  ros__parameters:\n    seed: 4\n")
    assert p.seed == 4
    p = NodeParams.from_yaml("/**:\n  ros__parameters:\n    mode: build_visual_map\n")
    assert p.allow_mapping


def test_ros_node_command_without_rclpy_says_what_to_install(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import symloc.ros.node as node_mod
    from symloc.cli.main import main

    monkeypatch.setattr(node_mod, "rclpy_available", lambda: False)
    params = tmp_path / "p.yaml"
    params.write_text("symloc:\n  ros__parameters: {}\n")
    assert main(["ros", "node", "--params", str(params)]) == 2
    assert "pip install '.[ros]' in symloc's checkout" in capsys.readouterr().err
    assert main(["ros", "check-params", str(params)]) == 0


def _png_header(width: int, height: int) -> bytes:
    """A PNG signature and IHDR declaring ``width x height`` (then garbage: never decoded)."""
    import struct
    import zlib

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    chunk = struct.pack(">I", 13) + b"IHDR" + ihdr + struct.pack(">I", zlib.crc32(b"IHDR" + ihdr))
    return b"\x89PNG\r\n\x1a\n" + chunk + b"\x00" * 200


def test_images_are_bounded_and_only_decoded_when_requested() -> None:
    import tracemalloc

    capture = _ambiguous(Request(RequestKind.CAPTURE_IMAGE))
    core, loc, warns = _core([LOST, capture], max_image_pixels=1000)
    core.on_map(_map_msg())
    core.on_odom(_odom_msg(1.0))
    big = {"header": {"stamp": {"sec": 1, "nanosec": 0}, "frame_id": "camera"}, "format": "png"}
    bomb = _msg(
        "sensor_msgs/msg/CompressedImage",
        {**big, "data": np.frombuffer(_png_header(16000, 16000), np.uint8)},
    )
    core.on_compressed_image(bomb)  # nothing requested: not decoded, not kept, not an error
    assert core.received["image"] == 1
    assert not core.dropped
    core.on_scan(_scan_msg(1.0))
    out = core.on_scan(_scan_msg(1.0))
    assert out.capture is not None
    tracemalloc.start()
    core.on_compressed_image(bomb)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 5_000_000  # refused from its header, not decoded (256 MP would be 768 MB)
    assert core.dropped["image: malformed"] == 1
    assert any("16000 x 16000" in w and "at most 1,000" in w for w in warns)
    raw = image_to_fields(np.zeros((40, 30, 3), np.uint8), stamp=1.0)  # 1200 pixels > 1000
    core.on_image(_msg("sensor_msgs/msg/Image", raw))
    assert core.dropped["image: malformed"] == 2
    ok = image_to_fields(np.zeros((20, 30, 3), np.uint8), stamp=1.0)
    core.on_image(_msg("sensor_msgs/msg/Image", ok))
    core.on_scan(_scan_msg(1.0))
    assert loc.calls[-1][2] is not None
    assert loc.calls[-1][2].shape == (20, 30, 3)


def _axis_estimate() -> Estimate:
    from symloc.localizer.types import AxisPose

    ends = np.array([[1.0, 2.0], [13.0, 2.0]])
    cov = np.diag([12.0**2 / 12.0, 0.05**2, math.radians(1.0) ** 2])
    axis = AxisPose(np.array([7.0, 2.0, 0.1]), cov, ends, open_ends=1)
    hyps = tuple(Hypothesis(np.array([*e, 0.1]), 0.5) for e in ends)
    return Estimate(Status.AXIS, hypotheses=hyps, reason="heading decided", axis=axis)


def test_an_axis_estimate_goes_on_its_own_topic_never_amcl_pose_nor_map_to_odom() -> None:
    from symloc.ros.requests import status_from_msg

    core, _, _ = _core([TRACK, _axis_estimate()])
    core.on_map(_map_msg())
    core.on_odom(_odom_msg(1.0))
    assert core.on_scan(_scan_msg(1.0)).tf is not None  # tracking: map -> odom sent
    core.on_odom(_odom_msg(1.1))
    out = core.on_scan(_scan_msg(1.1))
    assert out.estimate.status is Status.AXIS
    assert out.amcl_pose is None  # nav2 never reads it as a localized pose
    assert out.tf is None  # map -> odom withdrawn (left to age)
    assert out.axis_pose is not None
    assert out.axis_pose["header"]["frame_id"] == "map"
    cov6 = np.asarray(out.axis_pose["pose"]["covariance"], float).reshape(6, 6)
    assert cov6[0, 0] == pytest.approx(12.0)  # 12 m segment along x: (12 m)^2 / 12
    assert cov6[1, 1] == pytest.approx(0.05**2)
    assert cov6[5, 5] == pytest.approx(math.radians(1.0) ** 2)
    diag = out.status["status"][0]
    assert diag["level"] == 1  # WARN, as ambiguous
    assert diag["message"].startswith("axis: ")
    values = {kv["key"]: kv["value"] for kv in diag["values"]}
    assert values["status"] == "axis"
    assert values["pose"] == ""  # not a pose published as tracking
    assert [float(v) for v in values["axis_ends"].split()] == [1.0, 2.0, 13.0, 2.0]
    assert float(values["axis_length"]) == pytest.approx(12.0)
    stds = [float(v) for v in values["axis_std"].split()]
    assert stds == pytest.approx([12.0 / math.sqrt(12.0), 0.05, math.radians(1.0)])
    assert values["axis_open_ends"] == "1"
    assert "not updated since" in values["map_to_odom"] or "never" in values["map_to_odom"]
    markers = out.candidates["markers"]
    line = [m for m in markers if m.get("ns") == "symloc_axis"]
    assert len(line) == 1
    assert [p["x"] for p in line[0]["points"]] == [1.0, 13.0]
    # the dicts build real messages, and a driver reads the axis back
    _msg("geometry_msgs/msg/PoseWithCovarianceStamped", out.axis_pose)
    _msg("visualization_msgs/msg/MarkerArray", out.candidates)
    parsed = status_from_msg(_msg("diagnostic_msgs/msg/DiagnosticArray", out.status))
    assert parsed.status is Status.AXIS
    assert parsed.pose is None
    np.testing.assert_allclose(parsed.axis_pose, [7.0, 2.0, 0.1])
    np.testing.assert_allclose(parsed.axis_ends, [[1.0, 2.0], [13.0, 2.0]])
