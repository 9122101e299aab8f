"""TF without tf2 (symloc.ros.tf) and the node logic's use of it (NodeCore with use_tf)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_typestore

from symloc.errors import DataFormatError
from symloc.geometry import compose
from symloc.grid import OccupancyGrid
from symloc.localizer import Estimate, Hypothesis, Status
from symloc.msgs import (
    build_rosbags,
    grid_to_fields,
    pose_with_covariance_to_fields,
    scan_to_fields,
)
from symloc.odometry import OdometryReading
from symloc.ros.core import NodeCore
from symloc.ros.params import NodeParams
from symloc.ros.tf import (
    MapToOdom,
    TransformTree,
    laser_mount,
    map_from_odom,
    matrix_from_planar,
    odometry_from_transform,
    planar,
    transform_fields,
    transforms_from_msg,
)
from symloc.scan import LaserScan

TS = get_typestore(Stores.ROS2_JAZZY)
#: a laser 0.2 m ahead, 0.2 m up, turned over about y: upside down, looking back
LASER_Q = (0.0, 1.0, 0.0, 0.0)


def _tf(
    parent: str, child: str, xyz: tuple[float, ...], q: tuple[float, ...], stamp: float = 0.0
) -> dict:
    sec = int(stamp)
    return {
        "header": {
            "stamp": {"sec": sec, "nanosec": round((stamp - sec) * 1e9)},
            "frame_id": parent,
        },
        "child_frame_id": child,
        "transform": {
            "translation": dict(zip("xyz", xyz, strict=True)),
            "rotation": dict(zip("xyzw", q, strict=True)),
        },
    }


def _msg(*transforms: dict) -> object:
    return build_rosbags(TS, "tf2_msgs/msg/TFMessage", {"transforms": list(transforms)})


def _yaw_q(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def test_transforms_from_a_tf_message() -> None:
    ts = transforms_from_msg(_msg(_tf("base_link", "/laser", (0.2, 0.0, 0.2), LASER_Q, 1.5)))
    assert len(ts) == 1
    t = ts[0]
    assert (t.parent, t.child, t.stamp) == ("base_link", "laser", 1.5)
    np.testing.assert_allclose(t.matrix[:3, 3], [0.2, 0.0, 0.2])
    np.testing.assert_allclose(t.matrix[:3, :3], np.diag([-1.0, 1.0, -1.0]), atol=1e-12)


@pytest.mark.parametrize(
    ("bad", "match"),
    [
        (_tf("base_link", "laser", (0, 0, 0), (0, 0, 0, 0)), "non-zero finite quaternion"),
        (_tf("", "laser", (0, 0, 0), (0, 0, 0, 1)), "non-empty frames"),
        (_tf("base_link", "laser", (math.nan, 0, 0), (0, 0, 0, 1)), "translation.x"),
    ],
)
def test_malformed_transforms_are_refused(bad: dict, match: str) -> None:
    with pytest.raises(DataFormatError, match=match):
        transforms_from_msg(_msg(bad))


def test_tree_looks_up_across_frames_both_ways() -> None:
    tree = TransformTree()
    for t in transforms_from_msg(
        _msg(
            _tf("base_footprint", "base_link", (0.0, 0.0, 0.1), _yaw_q(0.0)),
            _tf("base_link", "laser", (0.2, 0.0, 0.2), LASER_Q),
            _tf("base_link", "camera", (0.1, 0.05, 0.3), _yaw_q(0.3)),
        )
    ):
        tree.add(t, static=True)
    m = tree.lookup("base_footprint", "laser")
    assert m is not None
    np.testing.assert_allclose(m[:3, 3], [0.2, 0.0, 0.3])
    back = tree.lookup("laser", "base_footprint")
    assert back is not None
    np.testing.assert_allclose(back @ m, np.eye(4), atol=1e-12)
    cam_from_laser = tree.lookup("camera", "laser")  # siblings: through their common parent
    assert cam_from_laser is not None
    np.testing.assert_allclose(
        cam_from_laser,
        np.linalg.inv(tree.lookup("base_link", "camera")) @ tree.lookup("base_link", "laser"),
    )
    assert tree.lookup("base_footprint", "nowhere") is None
    assert "laser" in tree
    assert "base_footprint" in tree
    assert "nowhere" not in tree


def test_an_older_dynamic_transform_is_ignored() -> None:
    tree = TransformTree()
    (new,) = transforms_from_msg(_msg(_tf("odom", "base_footprint", (1.0, 0, 0), _yaw_q(0), 2.0)))
    (old,) = transforms_from_msg(_msg(_tf("odom", "base_footprint", (0.5, 0, 0), _yaw_q(0), 1.0)))
    assert tree.add(new, static=False)
    assert not tree.add(old, static=False)
    assert tree.lookup("odom", "base_footprint")[0, 3] == 1.0  # type: ignore[index]


@pytest.mark.parametrize(
    ("q", "upside_down", "yaw"),
    [
        (_yaw_q(0.4), False, 0.4),  # upright, turned left
        ((1.0, 0.0, 0.0, 0.0), True, 0.0),  # rolled over: still looking ahead
        (LASER_Q, True, math.pi),  # pitched over: looking back
    ],
)
def test_laser_mount(q: tuple[float, ...], upside_down: bool, yaw: float) -> None:
    (t,) = transforms_from_msg(_msg(_tf("base_link", "laser", (0.2, -0.1, 0.2), q)))
    mount = laser_mount(t.matrix)
    assert mount.upside_down is upside_down
    assert math.remainder(mount.pose[2] - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(mount.pose[:2], [0.2, -0.1])
    assert mount.level


def test_a_tilted_laser_is_not_level() -> None:
    q = (math.sin(math.radians(15)), 0.0, 0.0, math.cos(math.radians(15)))  # 30 deg roll
    (t,) = transforms_from_msg(_msg(_tf("base_link", "laser", (0, 0, 0), q)))
    mount = laser_mount(t.matrix)
    assert mount.tilt == pytest.approx(math.radians(30))
    assert not mount.level


def test_odometry_from_tf_through_a_static_link() -> None:
    tree = TransformTree()
    (link,) = transforms_from_msg(_msg(_tf("base_footprint", "base_link", (0.1, 0, 0), _yaw_q(0))))
    tree.add(link, static=True)
    (odom,) = transforms_from_msg(_msg(_tf("odom", "base_link", (2.0, 1.0, 0), _yaw_q(0.5), 3.0)))
    reading = odometry_from_transform(odom, tree, odom_frame="odom", base_frame="base_footprint")
    assert reading is not None
    assert reading.stamp == 3.0
    # odom_from_base_footprint = odom_from_base_link * inverse(base_footprint_from_base_link)
    want = compose([2.0, 1.0, 0.5], [-0.1, 0.0, 0.0])
    np.testing.assert_allclose(reading.pose, want, atol=1e-12)
    (other,) = transforms_from_msg(_msg(_tf("map", "odom", (0, 0, 0), _yaw_q(0))))
    assert (
        odometry_from_transform(other, tree, odom_frame="odom", base_frame="base_footprint") is None
    )


poses = st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-math.pi, math.pi)).map(
    np.array
)


@given(poses, poses)
def test_map_from_odom_composed_with_odometry_is_the_map_pose(
    map_pose: np.ndarray, odom_pose: np.ndarray
) -> None:
    m = map_from_odom(map_pose, odom_pose)
    back = compose(m, odom_pose)
    np.testing.assert_allclose(back[:2], map_pose[:2], atol=1e-9)
    assert math.remainder(back[2] - map_pose[2], 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(planar(matrix_from_planar(m)), m, atol=1e-12)


TRACK = Estimate(
    Status.TRACKING,
    pose=np.array([1.0, 2.0, 0.5]),
    covariance=np.diag([1e-4, 1e-4, 1e-5]),
    hypotheses=(Hypothesis(np.array([1.0, 2.0, 0.5]), 1.0),),
    reason="tracking",
)
LOST = Estimate(Status.LOST, reason="claim withdrawn")


def test_map_to_odom_is_sent_only_with_a_confirmed_pose() -> None:
    policy = MapToOdom(global_frame="map", odom_frame="odom", tolerance=1.0)
    assert policy.step(LOST, 10.0, [0, 0, 0]) is None
    assert policy.describe(10.0) == "never sent (no pose earned yet)"
    out = policy.step(TRACK, 11.0, [0.5, 0.0, 0.1])
    assert out is not None
    (t,) = out["transforms"]
    assert t["header"]["frame_id"] == "map"
    assert t["child_frame_id"] == "odom"
    assert t["header"]["stamp"] == {"sec": 12, "nanosec": 0}  # scan time + transform_tolerance
    assert policy.describe(11.0).startswith("sent, stamped 12.000")
    assert policy.step(LOST, 11.1, [0.5, 0.0, 0.1]) is None  # not re-stamped: it ages
    assert policy.describe(11.1).startswith("not updated since the scan at 11.000")
    off = MapToOdom(global_frame="map", odom_frame="odom", tolerance=1.0, enabled=False)
    assert off.step(TRACK, 11.0, [0, 0, 0]) is None
    assert "tf_broadcast false" in off.describe(11.0)


# ---------------------------------------------------------------- NodeCore with TF


class Recorder:
    """A localizer that records the scans it is given and answers from a script."""

    def __init__(self, script: list[Estimate]) -> None:
        self.script = script
        self.scans: list[LaserScan] = []
        self.reset = 0
        self.poses_set: list[np.ndarray] = []
        self.last_result = None
        #: Localizer.holds_pose: True while the script's estimates are tracking or withheld
        self.holds_pose = False

    def update(self, odom, scan, image=None):  # type: ignore[no-untyped-def]
        self.scans.append(scan)
        return self.script[min(len(self.scans), len(self.script)) - 1]

    def set_pose(self, pose, cov):  # type: ignore[no-untyped-def]
        self.poses_set.append(np.asarray(pose))

    def reset_global(self) -> None:
        self.reset += 1

    def force_update(self) -> None:
        self.forced = getattr(self, "forced", 0) + 1


def _core(
    script: list[Estimate], **params: object
) -> tuple[NodeCore, list[tuple[object, NodeParams]], list[Recorder]]:
    built: list[tuple[object, NodeParams]] = []
    locs: list[Recorder] = []

    def factory(grid: object, p: NodeParams) -> Recorder:
        built.append((grid, p))
        locs.append(Recorder(script))
        return locs[-1]

    core = NodeCore(
        NodeParams(base_frame_id="base_footprint", **params), factory=factory, use_tf=True
    )  # type: ignore[arg-type]
    core.set_map(OccupancyGrid(np.zeros((40, 40), np.int8), 0.1))
    return core, built, locs


def _scan(stamp: float) -> object:
    scan = LaserScan(
        -math.pi / 2,
        math.pi / 180,
        0.1,
        10.0,
        np.linspace(1.0, 2.0, 181),
        stamp=stamp,
        frame_id="laser",
    )
    return build_rosbags(TS, "sensor_msgs/msg/LaserScan", scan_to_fields(scan))


def _static_laser(core: NodeCore) -> None:
    core.on_tf_static(
        _msg(
            _tf("base_footprint", "base_link", (0.0, 0.0, 0.1), _yaw_q(0.0)),
            _tf("base_link", "laser", (0.2, 0.0, 0.2), LASER_Q),
        )
    )


def _odom(core: NodeCore, stamp: float, pose: tuple[float, float, float]) -> None:
    core.on_tf(_msg(transform_fields(pose, stamp=stamp, parent="odom", child="base_footprint")))


def test_scans_wait_for_the_laser_on_tf_static() -> None:
    core, built, _ = _core([TRACK])
    _odom(core, 1.0, (0.0, 0.0, 0.0))
    assert not core.on_scan(_scan(1.0)).used
    assert core.dropped["scan: no laser pose"] == 1
    _static_laser(core)
    _odom(core, 1.1, (0.0, 0.0, 0.0))
    assert core.on_scan(_scan(1.1)).used
    # rebuilt for the mount: 0.2 m ahead, looking back (the upright frame of the turned-over laser)
    lp = built[-1][1].laser_pose
    assert lp[:2] == pytest.approx((0.2, 0.0))
    assert abs(abs(lp[2]) - math.pi) < 1e-9


def test_an_upside_down_laser_is_mirrored_before_the_localizer() -> None:
    core, _, locs = _core([TRACK])
    _static_laser(core)
    _odom(core, 1.0, (0.0, 0.0, 0.0))
    core.on_scan(_scan(1.0))
    seen = locs[-1].scans[-1]
    # raw beam i at angle a_i is at -a_i upright: the first beam seen is the raw last one
    assert seen.angle_min == pytest.approx(-math.pi / 2)
    assert seen.ranges[0] == pytest.approx(2.0, abs=1e-6)
    assert seen.ranges[-1] == pytest.approx(1.0)


def test_odometry_comes_from_tf_and_map_to_odom_goes_out_with_tracking_only() -> None:
    core, _, _ = _core([LOST, TRACK, LOST])
    _static_laser(core)
    _odom(core, 1.0, (0.0, 0.0, 0.0))
    _odom(core, 2.0, (1.0, 0.0, 0.0))
    out = core.on_scan(_scan(1.5))  # odometry interpolated at the scan's stamp
    assert out is not None
    assert out.tf is None
    _odom(core, 3.0, (1.0, 0.0, 0.0))
    out = core.on_scan(_scan(2.5))
    assert out is not None
    assert out.tf is not None
    (t,) = out.tf["transforms"]
    assert t["header"]["stamp"] == {"sec": 3, "nanosec": 500_000_000}
    q = t["transform"]["rotation"]
    m = np.array(
        [
            t["transform"]["translation"]["x"],
            t["transform"]["translation"]["y"],
            2 * math.atan2(q["z"], q["w"]),
        ]
    )
    np.testing.assert_allclose(compose(m, [1.0, 0.0, 0.0]), TRACK.pose, atol=1e-9)
    values = {v["key"]: v["value"] for v in out.status["status"][0]["values"]}
    assert values["map_to_odom"].startswith("sent, stamped 3.500")
    out = core.on_scan(_scan(2.9))
    assert out is not None
    assert out.tf is None
    values = {v["key"]: v["value"] for v in out.status["status"][0]["values"]}
    assert values["map_to_odom"].startswith("not updated since the scan at 2.500")


def test_tf_broadcast_false_sends_nothing() -> None:
    core, _, _ = _core([TRACK], tf_broadcast=False)
    _static_laser(core)
    _odom(core, 1.0, (0.0, 0.0, 0.0))
    out = core.on_scan(_scan(1.0))
    assert out is not None
    assert out.estimate.status is Status.TRACKING
    assert out.tf is None


def test_laser_pose_from_parameters_without_tf() -> None:
    core, built, locs = _core(
        [TRACK],
        laser_pose_source="parameters",
        laser_pose=(0.2, 0.0, math.pi),
        laser_upside_down=True,
    )
    _odom(core, 1.0, (0.0, 0.0, 0.0))
    assert core.on_scan(_scan(1.0)) is not None  # no /tf_static needed
    assert built[-1][1].laser_pose == (0.2, 0.0, math.pi)
    assert locs[-1].scans[-1].ranges[0] == pytest.approx(2.0, abs=1e-6)  # mirrored


def test_initial_pose_from_the_past_is_carried_by_odometry() -> None:
    core, _, locs = _core([TRACK])
    _odom(core, 1.0, (0.0, 0.0, 0.0))
    _odom(core, 2.0, (1.0, 0.0, math.pi / 2))
    fields = pose_with_covariance_to_fields([1.0, 1.5, 0.0], np.eye(3) * 0.01, stamp=1.0)
    core.on_initialpose(build_rosbags(TS, "geometry_msgs/msg/PoseWithCovarianceStamped", fields))
    np.testing.assert_allclose(locs[-1].poses_set[-1], [2.0, 1.5, math.pi / 2], atol=1e-9)


def test_first_map_only_and_the_services() -> None:
    core, built, locs = _core([TRACK], first_map_only=True)
    n = len(built)
    core.on_map(
        build_rosbags(
            TS,
            "nav_msgs/msg/OccupancyGrid",
            grid_to_fields(OccupancyGrid(np.zeros((50, 50), np.int8), 0.1), stamp=0.0),
        )
    )
    assert len(built) == n
    assert core.grid is not None
    assert core.grid.width == 40
    assert core.reinitialize_global()
    assert locs[-1].reset == 1
    assert core.request_nomotion_update()
    assert locs[-1].forced == 1


def test_odometry_reading_from_tf_is_used_for_scans() -> None:
    core, _, _ = _core([TRACK])
    _static_laser(core)
    _odom(core, 5.0, (2.0, 3.0, 0.25))
    out = core.on_scan(_scan(5.0))
    assert out is not None
    assert core.received["tf"] == 1
    assert core.received["tf_static"] == 1
    assert isinstance(core._odom.at(5.0, 1.0), OdometryReading)


# ---------------------------------------------------------------- issue 27: nav2's pairing


WITHHELD = Estimate(Status.LOST, reason="claim withheld: std exceeds")


def test_map_to_odom_is_re_sent_while_the_pose_is_held() -> None:
    policy = MapToOdom(global_frame="map", odom_frame="odom", tolerance=1.0)
    assert policy.step(WITHHELD, 10.0, [0, 0, 0], holds=True) is None  # nothing earned yet
    first = policy.step(TRACK, 11.0, [0.5, 0.0, 0.1])
    assert first is not None
    again = policy.step(WITHHELD, 11.2, [0.7, 0.0, 0.1], holds=True)  # one claim withheld
    assert again is not None
    assert again["transforms"][0]["header"]["stamp"] == {"sec": 12, "nanosec": 200_000_000}
    # the same map -> odom: the last confirmed pose carried by odometry
    assert again["transforms"][0]["transform"] == first["transforms"][0]["transform"]
    assert policy.describe(11.2).startswith("re-sent, stamped 12.200")
    assert policy.step(LOST, 11.4, [0.9, 0.0, 0.1]) is None  # the localizer gave the pose up
    assert policy.step(WITHHELD, 11.6, [0.9, 0.0, 0.1], holds=True) is None  # until earned again
    assert policy.resend(11.8) is None


def test_a_scan_waits_for_the_odometry_at_its_stamp() -> None:
    core, _, locs = _core([TRACK])
    _static_laser(core)
    _odom(core, 1.0, (0.0, 0.0, 0.0))
    assert core.offer_scan(_scan_obj(1.1), now=100.0) == []  # held: odometry only up to 1.0
    assert core.held_scans == 1
    _odom(core, 1.2, (0.2, 0.0, 0.0))
    (out,) = core.ready_scans(now=100.05)
    assert out.used
    assert out.tf is not None
    # paired with the odometry at 1.1, interpolated (not the older reading at 1.0)
    tf_pose = out.tf["transforms"][0]["transform"]["translation"]
    assert tf_pose["x"] == pytest.approx(1.0 - 0.1 * math.cos(0.5), abs=1e-9)
    assert len(locs[-1].scans) == 1


def test_a_scan_whose_odometry_never_comes_is_dropped_after_the_tolerance() -> None:
    core, _, _ = _core([TRACK])
    _static_laser(core)
    _odom(core, 1.0, (0.0, 0.0, 0.0))
    assert core.offer_scan(_scan_obj(1.1), now=100.0) == []
    assert core.ready_scans(now=100.9) == []  # still within transform_tolerance (1 s)
    (out,) = core.ready_scans(now=101.2)
    assert not out.used
    assert core.dropped["scan: no odometry at its stamp within transform_tolerance"] == 1
    assert "no odometry at its stamp" in out.estimate.reason


def test_a_pending_initial_pose_survives_every_rebuild() -> None:
    """Issue 27 item 2: the pose set before the first scan on a robot whose laser is not at the
    base origin was lost when the localizer was rebuilt for the laser's mount."""
    core, built, locs = _core([WITHHELD])
    _odom(core, 1.0, (0.0, 0.0, 0.0))
    start = np.array([1.0, 1.5, 0.3])
    assert core.set_initial_pose(start, np.eye(3) * 0.01)
    _static_laser(core)
    _odom(core, 1.1, (0.1, 0.0, 0.0))
    core.on_scan(_scan(1.1))  # the mount is found: rebuilt, the pose seeded at this scan
    assert len(built) == 2
    np.testing.assert_allclose(locs[-1].poses_set[-1], compose(start, [0.1, 0, 0]), atol=1e-9)
    core.reconfigure(dataclasses.replace(core.params, transform_tolerance=0.5))  # parameters
    _odom(core, 1.2, (0.2, 0.0, 0.0))
    core.on_scan(_scan(1.2))
    np.testing.assert_allclose(locs[-1].poses_set[-1], compose(start, [0.2, 0, 0]), atol=1e-9)
    core.set_map(OccupancyGrid(np.zeros((45, 45), np.int8), 0.1))  # a new map
    core.reconfigure(core.params)  # and a rebuild before the next scan: still kept
    _odom(core, 1.3, (0.3, 0.0, 0.0))
    core.on_scan(_scan(1.3))
    assert len(built) == 5
    np.testing.assert_allclose(locs[-1].poses_set[-1], compose(start, [0.3, 0, 0]), atol=1e-9)
    assert core.reinitialize_global()  # forgotten: no rebuild brings it back
    core.set_map(OccupancyGrid(np.zeros((40, 40), np.int8), 0.1))
    core.on_scan(_scan(1.3))
    assert locs[-1].poses_set == []


def _scan_obj(stamp: float) -> LaserScan:
    return LaserScan(
        -math.pi / 2,
        math.pi / 180,
        0.1,
        10.0,
        np.linspace(1.0, 2.0, 181),
        stamp=stamp,
        frame_id="laser",
    )
