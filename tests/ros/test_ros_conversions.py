"""Round trips of the ROS message conversions through rosbags dataclasses and look-alikes."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_typestore

from symloc.errors import DataFormatError
from symloc.grid import OccupancyGrid
from symloc.msgs import (
    build_rosbags,
    compressed_image_from_msg,
    compressed_image_to_fields,
    covariance_to_ros,
    grid_from_msg,
    grid_to_fields,
    image_from_msg,
    image_to_fields,
    odometry_from_msg,
    odometry_to_fields,
    pose_array_to_fields,
    pose_with_covariance_from_msg,
    pose_with_covariance_to_fields,
    scan_from_msg,
    scan_to_fields,
)
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan

TS2 = get_typestore(Stores.ROS2_HUMBLE)
TS1 = get_typestore(Stores.ROS1_NOETIC)


def _scan(n: int = 90, stamp: float = 12.5) -> LaserScan:
    rng = np.random.default_rng(0)
    r = rng.uniform(0.5, 5.0, n)
    r[3] = np.inf
    r[7] = np.nan
    return LaserScan(-math.pi, 2 * math.pi / n, 0.12, 8.0, r, stamp=stamp, frame_id="laser")


def _cdr_round_trip(msgtype: str, fields: dict) -> object:
    msg = build_rosbags(TS2, msgtype, fields)
    return TS2.deserialize_cdr(TS2.serialize_cdr(msg, msgtype), msgtype)


def test_scan_round_trip_through_cdr() -> None:
    scan = _scan()
    back = scan_from_msg(_cdr_round_trip("sensor_msgs/msg/LaserScan", scan_to_fields(scan)))
    assert len(back) == len(scan)
    np.testing.assert_allclose(back.ranges, scan.ranges.astype(np.float32), equal_nan=True)
    assert back.angle_min == pytest.approx(scan.angle_min, abs=1e-6)
    assert back.angle_increment == pytest.approx(scan.angle_increment, rel=1e-6)
    assert back.stamp == pytest.approx(12.5)
    assert back.frame_id == "laser"
    assert np.isnan(back.ranges[7])
    assert np.isposinf(back.ranges[3])


def test_scan_round_trip_through_ros1_serialisation() -> None:
    scan = _scan(stamp=3.25)
    msgtype = "sensor_msgs/msg/LaserScan"
    msg = build_rosbags(TS1, msgtype, scan_to_fields(scan))
    back = scan_from_msg(TS1.deserialize_ros1(TS1.serialize_ros1(msg, msgtype), msgtype))
    assert back.stamp == pytest.approx(3.25)
    np.testing.assert_allclose(back.ranges, scan.ranges.astype(np.float32), equal_nan=True)


def test_clockwise_scan_is_reversed() -> None:
    msg = build_rosbags(
        TS2,
        "sensor_msgs/msg/LaserScan",
        {
            "angle_min": 1.0,
            "angle_increment": -0.5,
            "range_min": 0.1,
            "range_max": 10.0,
            "ranges": np.array([1.0, 2.0, 3.0], np.float32),
        },
    )
    scan = scan_from_msg(msg)
    assert scan.angle_increment == pytest.approx(0.5)
    np.testing.assert_allclose(scan.angles, [0.0, 0.5, 1.0])
    np.testing.assert_allclose(scan.ranges, [3.0, 2.0, 1.0])


def _scan_ns(**over: object) -> SimpleNamespace:
    base = {
        "header": SimpleNamespace(stamp=SimpleNamespace(sec=1, nanosec=0), frame_id="laser"),
        "angle_min": -1.0,
        "angle_max": 1.0,
        "angle_increment": 0.5,
        "time_increment": 0.0,
        "scan_time": 0.1,
        "range_min": 0.1,
        "range_max": 5.0,
        "ranges": [1.0, 2.0, 3.0, 4.0, 5.0],
        "intensities": [],
    }
    base.update(over)
    return SimpleNamespace(**base)


@pytest.mark.parametrize(
    ("over", "match"),
    [
        ({"angle_increment": float("nan")}, r"LaserScan\.angle_increment"),
        ({"angle_increment": 0.0}, r"LaserScan\.angle_increment"),
        ({"range_max": 0.05}, r"LaserScan\.range_max"),
        ({"ranges": []}, r"LaserScan\.ranges"),
        ({"ranges": ["a", "b"]}, r"LaserScan\.ranges"),
        ({"intensities": [1.0]}, r"LaserScan\.intensities"),
        ({"header": SimpleNamespace(frame_id="x")}, r"LaserScan\.header\.stamp"),
        (
            {"header": SimpleNamespace(stamp=SimpleNamespace(sec=1, nanosec=0), frame_id=3)},
            r"frame_id",
        ),
    ],
)
def test_malformed_scan_names_the_field(over: dict, match: str) -> None:
    with pytest.raises(DataFormatError, match=match):
        scan_from_msg(_scan_ns(**over))


def test_scan_missing_field_is_named() -> None:
    msg = _scan_ns()
    del msg.range_min
    with pytest.raises(DataFormatError, match=r"LaserScan\.range_min: field is missing"):
        scan_from_msg(msg)


def test_scan_with_wrong_beam_count_is_rejected() -> None:
    with pytest.raises(DataFormatError, match=r"expected 360 readings"):
        scan_from_msg(_scan_ns(), expected_beams=360)


def test_ros1_style_stamp_is_read() -> None:
    msg = _scan_ns(
        header=SimpleNamespace(stamp=SimpleNamespace(secs=4, nsecs=500_000_000), frame_id="/laser")
    )
    scan = scan_from_msg(msg)
    assert scan.stamp == pytest.approx(4.5)
    assert scan.frame_id == "laser"


@settings(max_examples=40, deadline=None)
@given(
    x=st.floats(-100, 100),
    y=st.floats(-100, 100),
    th=st.floats(-math.pi + 1e-6, math.pi),
    t=st.floats(0, 1e6),
)
def test_odometry_round_trip(x: float, y: float, th: float, t: float) -> None:
    reading = OdometryReading(np.array([x, y, th]), t)
    back = odometry_from_msg(_cdr_round_trip("nav_msgs/msg/Odometry", odometry_to_fields(reading)))
    np.testing.assert_allclose(back.pose[:2], [x, y], atol=1e-9)
    assert abs(math.remainder(back.pose[2] - th, 2 * math.pi)) < 1e-9
    assert back.stamp == pytest.approx(t, abs=1e-6)


def test_odometry_nan_pose_names_the_field() -> None:
    fields = odometry_to_fields(OdometryReading(np.zeros(3), 1.0))
    fields["pose"]["pose"]["position"]["x"] = float("nan")
    msg = build_rosbags(TS2, "nav_msgs/msg/Odometry", fields)
    with pytest.raises(DataFormatError, match=r"Odometry\.pose\.pose\.position\.x"):
        odometry_from_msg(msg)


def test_zero_quaternion_is_rejected() -> None:
    fields = odometry_to_fields(OdometryReading(np.zeros(3), 1.0))
    fields["pose"]["pose"]["orientation"] = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 0.0}
    msg = build_rosbags(TS2, "nav_msgs/msg/Odometry", fields)
    with pytest.raises(DataFormatError, match=r"orientation: expected a unit quaternion"):
        odometry_from_msg(msg)


def test_grid_round_trip() -> None:
    rng = np.random.default_rng(1)
    data = rng.choice(np.array([-1, 0, 100, 50], np.int8), size=(7, 11))
    grid = OccupancyGrid(data, 0.05, np.array([-1.0, 2.0, 0.3]))
    back = grid_from_msg(
        _cdr_round_trip("nav_msgs/msg/OccupancyGrid", grid_to_fields(grid, stamp=1.0))
    )
    np.testing.assert_array_equal(back.data, data)
    assert back.resolution == pytest.approx(0.05)
    np.testing.assert_allclose(back.origin, [-1.0, 2.0, 0.3], atol=1e-12)


def test_grid_size_mismatch_names_the_field() -> None:
    grid = OccupancyGrid(np.zeros((4, 5), np.int8), 0.1)
    fields = grid_to_fields(grid, stamp=0.0)
    fields["info"]["width"] = 6
    with pytest.raises(DataFormatError, match=r"OccupancyGrid\.data: expected width x height"):
        grid_from_msg(build_rosbags(TS2, "nav_msgs/msg/OccupancyGrid", fields))


def test_grid_bad_values_and_resolution() -> None:
    grid = OccupancyGrid(np.zeros((2, 2), np.int8), 0.1)
    fields = grid_to_fields(grid, stamp=0.0)
    fields["data"] = np.array([0, 101, 0, 0], np.int8)
    with pytest.raises(DataFormatError, match=r"OccupancyGrid\.data: values"):
        grid_from_msg(build_rosbags(TS2, "nav_msgs/msg/OccupancyGrid", fields))
    fields = grid_to_fields(grid, stamp=0.0)
    fields["info"]["resolution"] = 0.0
    with pytest.raises(DataFormatError, match=r"OccupancyGrid\.info\.resolution"):
        grid_from_msg(build_rosbags(TS2, "nav_msgs/msg/OccupancyGrid", fields))


def _rgb(h: int = 6, w: int = 5) -> np.ndarray:
    return np.random.default_rng(2).integers(0, 256, (h, w, 3), dtype=np.uint8)


def test_image_round_trip_rgb8() -> None:
    img = _rgb()
    back = image_from_msg(_cdr_round_trip("sensor_msgs/msg/Image", image_to_fields(img, stamp=2.0)))
    np.testing.assert_array_equal(back, img)


@pytest.mark.parametrize("enc", ["bgr8", "8UC3", "bgra8", "rgba8", "mono8", "mono16"])
def test_image_encodings_with_row_padding(enc: str) -> None:
    img = _rgb()
    h, w, _ = img.shape
    if enc in ("bgr8", "8UC3"):
        px = img[:, :, ::-1]
    elif enc == "bgra8":
        px = np.dstack([img[:, :, ::-1], np.full((h, w), 255, np.uint8)])
    elif enc == "rgba8":
        px = np.dstack([img, np.full((h, w), 255, np.uint8)])
    elif enc == "mono8":
        px = img[:, :, :1]
    else:
        px = (img[:, :, 0].astype(np.uint16) * 256).astype(">u2").view(np.uint8).reshape(h, w, 2)
    row = px.reshape(h, -1)
    padded = np.hstack([row, np.zeros((h, 4), np.uint8)])
    msg = SimpleNamespace(
        height=h, width=w, encoding=enc, step=padded.shape[1], is_bigendian=1, data=padded.tobytes()
    )
    out = image_from_msg(msg)
    assert out.shape == (h, w, 3)
    if enc in ("mono8", "mono16"):
        np.testing.assert_array_equal(out[:, :, 1], img[:, :, 0])
    else:
        np.testing.assert_array_equal(out, img)


def test_image_unknown_encoding_is_named() -> None:
    msg = SimpleNamespace(
        height=2, width=2, encoding="yuv422", step=4, is_bigendian=0, data=b"\0" * 8
    )
    with pytest.raises(DataFormatError, match=r"Image\.encoding: unsupported encoding 'yuv422'"):
        image_from_msg(msg)


def test_image_short_data_is_named() -> None:
    msg = SimpleNamespace(
        height=4, width=4, encoding="rgb8", step=12, is_bigendian=0, data=b"\0" * 20
    )
    with pytest.raises(DataFormatError, match=r"Image\.data: expected height x step"):
        image_from_msg(msg)
    msg.step = 3
    with pytest.raises(DataFormatError, match=r"Image\.step"):
        image_from_msg(msg)


def test_compressed_image_png_round_trip_and_garbage() -> None:
    img = _rgb(16, 20)
    fields = compressed_image_to_fields(img, stamp=1.0)
    back = compressed_image_from_msg(_cdr_round_trip("sensor_msgs/msg/CompressedImage", fields))
    np.testing.assert_array_equal(back, img)
    bad = SimpleNamespace(format="jpeg", data=b"not a jpeg at all")
    with pytest.raises(DataFormatError, match=r"CompressedImage\.data: not an image format"):
        compressed_image_from_msg(bad)
    # a valid PNG header followed by garbage: the header passes, OpenCV refuses the rest
    png = bytes(np.asarray(fields["data"]).tobytes())
    truncated = SimpleNamespace(format="png", data=png[:40] + b"\x00" * 40)
    with pytest.raises(DataFormatError, match=r"CompressedImage\.data: OpenCV could not decode"):
        compressed_image_from_msg(truncated)
    with pytest.raises(DataFormatError, match=r"CompressedImage\.data: empty"):
        compressed_image_from_msg(SimpleNamespace(format="png", data=b""))


def test_pose_with_covariance_round_trip_and_nan() -> None:
    cov = np.array([[0.25, 0.01, 0.0], [0.01, 0.3, 0.02], [0.0, 0.02, 0.07]])
    fields = pose_with_covariance_to_fields([1.0, -2.0, 2.5], cov, stamp=5.0)
    msg = _cdr_round_trip("geometry_msgs/msg/PoseWithCovarianceStamped", fields)
    pose, back = pose_with_covariance_from_msg(msg)
    np.testing.assert_allclose(pose, [1.0, -2.0, 2.5], atol=1e-12)
    np.testing.assert_allclose(back, cov)
    fields["pose"]["covariance"] = covariance_to_ros(np.full((3, 3), np.nan))
    msg = build_rosbags(TS2, "geometry_msgs/msg/PoseWithCovarianceStamped", fields)
    with pytest.raises(DataFormatError, match=r"PoseWithCovarianceStamped\.pose\.covariance"):
        pose_with_covariance_from_msg(msg)


def test_pose_array_yaws() -> None:
    poses = np.array([[0.0, 1.0, 0.5], [2.0, 3.0, -3.0]])
    msg = _cdr_round_trip(
        "geometry_msgs/msg/PoseArray", pose_array_to_fields(poses, stamp=0.0, frame_id="map")
    )
    assert len(msg.poses) == 2
    yaw = [2 * math.atan2(p.orientation.z, p.orientation.w) for p in msg.poses]
    np.testing.assert_allclose(
        np.remainder(np.array(yaw) - poses[:, 2] + np.pi, 2 * np.pi) - np.pi, 0, atol=1e-12
    )


def test_build_rosbags_rejects_unknown_field_and_type() -> None:
    with pytest.raises(DataFormatError, match=r"sensor_msgs/msg/LaserScan\.bogus: no such field"):
        build_rosbags(TS2, "sensor_msgs/msg/LaserScan", {"bogus": 1})
    with pytest.raises(DataFormatError, match=r"nope/msg/X: message type not in the typestore"):
        build_rosbags(TS2, "nope/msg/X", {})
