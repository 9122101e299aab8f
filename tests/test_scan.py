from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from symloc.errors import DataFormatError
from symloc.scan import LaserScan


def make_scan(ranges: list[float] | np.ndarray, **kw: float) -> LaserScan:
    return LaserScan(
        angle_min=kw.get("angle_min", 0.0),
        angle_increment=kw.get("angle_increment", np.pi / 2),
        range_min=kw.get("range_min", 0.1),
        range_max=kw.get("range_max", 10.0),
        ranges=np.asarray(ranges, dtype=float),
    )


def test_to_points_eq_1_2_and_counts() -> None:
    scan = make_scan([1.0, 2.0, np.nan, np.inf, 0.05, 10.0, 3.0, -np.inf], angle_increment=0.5)
    p = scan.to_points()
    np.testing.assert_allclose(p.points[0], [1.0, 0.0])
    np.testing.assert_allclose(p.points[1], [2 * np.cos(0.5), 2 * np.sin(0.5)])
    np.testing.assert_array_equal(p.indices, [0, 1, 6])
    assert p.n_invalid == 3  # NaN, below range_min, -inf
    assert p.n_no_return == 2  # +inf, == range_max
    assert p.n_dropped == 5


def test_masks_partition_readings() -> None:
    scan = make_scan([1.0, np.nan, np.inf, 0.0, 12.0, 5.0], angle_increment=0.1)
    total = scan.valid_mask.astype(int) + scan.invalid_mask.astype(int) + scan.no_return_mask
    np.testing.assert_array_equal(total, 1)


def test_angles_and_angle_max() -> None:
    scan = LaserScan.from_angle_range(
        -np.pi, np.pi - 2 * np.pi / 360, np.ones(360), range_min=0.12, range_max=3.5
    )
    assert scan.angle_increment == pytest.approx(np.deg2rad(1.0))
    assert scan.angle_max == pytest.approx(np.pi - np.deg2rad(1.0))
    assert scan.angles.shape == (360,)
    assert not scan.angles.flags.writeable


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"angle_increment": -0.1}, "angle_increment: expected > 0"),
        ({"angle_increment": 0.0}, "angle_increment: expected > 0"),
        ({"angle_min": float("nan")}, "angle_min: expected a finite number"),
        ({"angle_increment": float("inf")}, "angle_increment: expected a finite number"),
        ({"range_min": -1.0}, "range_min: expected >= 0"),
        ({"range_max": 0.05}, "range_max: expected > range_min"),
    ],
)
def test_validation_errors_name_the_field(kwargs: dict[str, float], match: str) -> None:
    with pytest.raises(DataFormatError, match=match):
        make_scan([1.0, 2.0], **kwargs)


def test_intensity_length_mismatch() -> None:
    with pytest.raises(DataFormatError, match=r"intensities: expected 3 values"):
        LaserScan(0.0, 0.1, 0.1, 10.0, np.ones(3), intensities=np.ones(2))


def test_empty_and_2d_ranges_rejected() -> None:
    with pytest.raises(DataFormatError, match="at least one reading"):
        make_scan([])
    with pytest.raises(DataFormatError, match="1-D"):
        LaserScan(0.0, 0.1, 0.1, 10.0, np.ones((2, 2)))


def test_more_than_one_revolution_rejected() -> None:
    with pytest.raises(DataFormatError, match="more than one revolution"):
        LaserScan(0.0, np.deg2rad(2.0), 0.1, 10.0, np.ones(360))


def test_scan_is_immutable() -> None:
    scan = make_scan([1.0, 2.0])
    with pytest.raises(ValueError, match="read-only"):
        scan.ranges[0] = 3.0


@given(st.lists(st.one_of(st.floats(allow_nan=True, allow_infinity=True)), min_size=1, max_size=64))
def test_to_points_never_emits_non_finite(values: list[float]) -> None:
    scan = make_scan(values, angle_increment=0.05)
    p = scan.to_points()
    assert np.all(np.isfinite(p.points))
    assert len(p.points) + p.n_dropped == len(values)


def test_deskew_undoes_a_spinning_lidars_motion() -> None:
    from symloc.scan import deskew
    from symloc.sim.lidar import RPLIDAR_A2, LidarFaults, SimulatedLidar
    from symloc.sim.rooms import rectangle_room

    room = rectangle_room(6.0, 4.0)
    pose = np.array([0.4, -0.3, 0.2])
    c, s = np.cos(pose[2]), np.sin(pose[2])

    def off_wall_p95(scan: LaserScan) -> float:
        p = scan.to_points().points
        world = np.column_stack(
            [pose[0] + c * p[:, 0] - s * p[:, 1], pose[1] + s * p[:, 0] + c * p[:, 1]]
        )
        return float(np.percentile(room.world.distance(world), 95))

    still = SimulatedLidar(RPLIDAR_A2, LidarFaults(), 1).scan(room.world, pose)
    noise = off_wall_p95(still)  # the data-sheet range noise alone
    for twist in ((0.0, 1.0), (0.3, 0.0), (0.3, -0.8)):
        skewed = SimulatedLidar(RPLIDAR_A2, LidarFaults(motion_skew=True), 1).scan(
            room.world, pose, twist=twist
        )
        fixed = off_wall_p95(deskew(skewed, *twist))
        assert fixed < 1.3 * noise
        assert off_wall_p95(skewed) > 1.3 * fixed
    assert deskew(still, 0.3, 1.0) is still  # no time_increment: an instantaneous scan


def test_twist_between_readings() -> None:
    from symloc.odometry import OdometryReading, twist_between

    a = OdometryReading(np.array([1.0, 1.0, np.pi / 2]), 10.0)
    b = OdometryReading(np.array([1.0, 1.03, np.pi / 2 + 0.05]), 10.1)
    v, w = twist_between(a, b)
    assert v == pytest.approx(0.3)
    assert w == pytest.approx(0.5)
    back = OdometryReading(np.array([1.0, 0.97, np.pi / 2]), 10.1)
    assert twist_between(a, back)[0] == pytest.approx(-0.3)
    assert twist_between(b, a) == (0.0, 0.0)  # out of order
    assert twist_between(a, OdometryReading(b.pose, 12.0)) == (0.0, 0.0)  # too old


def test_mirror_flips_the_scan_and_is_its_own_inverse() -> None:
    from symloc.scan import mirror

    scan = LaserScan(
        -1.0,
        0.01,
        0.1,
        10.0,
        np.linspace(1.0, 3.0, 150),
        stamp=2.0,
        time_increment=1e-4,
        frame_id="laser",
    )
    flipped = mirror(scan)
    p, q = scan.to_points().points, flipped.to_points().points
    # the same end points seen from an upright frame: y negated (the beams in reverse order)
    np.testing.assert_allclose(q[::-1], p * [1.0, -1.0], atol=1e-12)
    assert flipped.angle_increment > 0
    assert flipped.time_increment == -1e-4
    assert flipped.stamp == scan.stamp
    back = mirror(flipped)
    np.testing.assert_allclose(back.ranges, scan.ranges)
    assert back.angle_min == pytest.approx(scan.angle_min)
    assert back.time_increment == scan.time_increment


def test_sensor_twist_of_an_offset_laser() -> None:
    from symloc.scan import sensor_twist

    assert sensor_twist(0.3, 0.0, [0.0, 0.0, 0.0]) == pytest.approx((0.3, 0.0, 0.0))
    # turning on the spot, a laser 0.2 m ahead moves sideways (to its left) at 0.2 w
    assert sensor_twist(0.0, 1.0, [0.2, 0.0, 0.0]) == pytest.approx((0.0, 0.2, 1.0))
    # facing backwards, forward motion is backwards for the laser
    assert sensor_twist(0.3, 0.0, [0.2, 0.0, np.pi]) == pytest.approx((-0.3, 0.0, 0.0))


def test_deskew_an_upside_down_laser_off_the_centre() -> None:
    """A laser 0.2 m ahead, upside down and looking back, on a robot driving along an arc:
    mirrored and deskewed with its own twist, its points land on the walls again."""
    from symloc.geometry import compose
    from symloc.scan import deskew, mirror, sensor_twist
    from symloc.sim.raycast import raycast
    from symloc.sim.rooms import rectangle_room

    room = rectangle_room(6.0, 4.0)
    base0 = np.array([0.4, -0.3, 0.2])
    mount = np.array([0.2, 0.0, np.pi])  # the upright frame of the turned-over laser
    v, w, n, dt = 0.3, -0.8, 720, 0.1 / 720
    t = np.arange(n) * dt
    # the base along its arc, the laser on it; raw beam i (laser frame angle a_i) is taken at
    # t_i and points at -a_i in the upright frame
    th = base0[2] + w * t
    bx = base0[0] + v / w * (np.sin(th) - np.sin(base0[2]))
    by = base0[1] - v / w * (np.cos(th) - np.cos(base0[2]))
    sensor = compose(np.column_stack([bx, by, th]), mount)
    a = -np.pi + np.arange(n) * (2 * np.pi / n)
    ranges = raycast(room.world, sensor[:, :2], (sensor[:, 2] - a)[:, None])[:, 0]
    raw = LaserScan(-np.pi, 2 * np.pi / n, 0.1, 12.0, ranges, time_increment=dt)
    at0 = compose(base0, mount)
    c, s = np.cos(at0[2]), np.sin(at0[2])

    def off_wall_p95(scan: LaserScan) -> float:
        p = scan.to_points().points
        world = np.column_stack(
            [at0[0] + c * p[:, 0] - s * p[:, 1], at0[1] + s * p[:, 0] + c * p[:, 1]]
        )
        return float(np.percentile(room.world.distance(world), 95))

    upright = mirror(raw)
    vx, vy, wz = sensor_twist(v, w, mount)
    fixed = off_wall_p95(deskew(upright, vx, wz, vy=vy))
    # as for a laser at the centre (the translation is undone to first order along each beam)
    assert fixed < 0.025
    assert off_wall_p95(upright) > 5 * fixed
    # the robot's twist alone (the laser taken for the centre) leaves an error
    assert off_wall_p95(deskew(upright, v, w)) > 2 * fixed


def test_scans_of_one_geometry_share_their_read_only_angles() -> None:
    """A log's scans hold one angle array between them (memory), which nobody can change."""
    a = LaserScan(-1.5, 0.01, 0.1, 30.0, np.ones(300))
    b = LaserScan(-1.5, 0.01, 0.1, 30.0, np.full(300, 2.0))
    c = LaserScan(-1.5, 0.01, 0.1, 30.0, np.ones(301))
    assert a.angles is b.angles
    assert not a.angles.flags.writeable
    assert c.angles is not a.angles
    np.testing.assert_array_equal(a.angles, -1.5 + 0.01 * np.arange(300))


def test_message_precision_is_what_a_bag_gives_back(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """A scan rounded to sensor_msgs/LaserScan's float32 is, bit for bit, the scan a bag gives
    back; rounding again changes nothing (the same object comes back)."""
    from symloc.io.rosbag import BagWriter, read_bag
    from symloc.scan import message_precision

    rng = np.random.default_rng(5)
    scan = LaserScan(
        -np.pi / 2,
        np.pi / 180,
        0.0,
        50.0,
        np.round(rng.uniform(0.5, 49.0, 181), 3),  # a CARMEN log's millimetres, as float64
        intensities=rng.uniform(0, 1, 181),
        stamp=1_000_000_000.123456,
        time_increment=1e-4 / 3,
        scan_time=0.1 / 3,
    )
    rounded = message_precision(scan)
    assert not np.array_equal(rounded.ranges, scan.ranges)  # float64 millimetres move
    np.testing.assert_array_equal(rounded.ranges, scan.ranges.astype(np.float32))
    assert rounded.angle_min == float(np.float32(-np.pi / 2)) != scan.angle_min
    assert message_precision(rounded) is rounded
    with BagWriter(tmp_path / "b") as w:
        w.write_scan(scan)
    (back,) = [m.value for m in read_bag(tmp_path / "b") if m.kind == "scan"]
    assert message_precision(back) is back  # a bag's scan is already at message precision
    for name in (
        "angle_min", "angle_increment", "range_min", "range_max", "time_increment", "scan_time"
    ):  # fmt: skip
        assert getattr(back, name) == getattr(rounded, name), name
    np.testing.assert_array_equal(back.ranges, rounded.ranges)
    np.testing.assert_array_equal(back.angles, rounded.angles)
    np.testing.assert_array_equal(back.intensities, rounded.intensities)
    assert rounded.stamp == scan.stamp
    assert rounded.frame_id == scan.frame_id


def test_message_precision_keeps_values_beyond_float32_finite() -> None:
    from symloc.scan import message_precision

    scan = LaserScan(0.0, 1e-3, 0.0, 1e300, np.array([np.nan, np.inf, 1.0, 1e39]))
    out = message_precision(scan)
    assert out.range_max == float(np.finfo(np.float32).max)
    assert np.isnan(out.ranges[0])
    np.testing.assert_array_equal(out.ranges[1:], [np.inf, 1.0, np.inf])
