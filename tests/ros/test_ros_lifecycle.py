"""The lifecycle node in-process: transitions, nav2's params files, runtime changes, poses."""

from __future__ import annotations

import math
import os
import random
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip("rclpy", reason="rclpy absent: pip install '.[ros]' in symloc's checkout")
pytest.importorskip("diagnostic_msgs.msg", reason="ROS message packages absent: symloc[ros]")

from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter

from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.grid.map_io import save_map
from symloc.localizer import Estimate, Status
from symloc.msgs import build_rclpy, odometry_to_fields, scan_to_fields
from symloc.odometry import OdometryReading
from symloc.ros.lifecycle import LocalizationNode, load_saved_pose, save_pose
from symloc.ros.params import NodeParams
from symloc.scan import LaserScan

DATA = Path(__file__).parent / "data" / "nav2"
OK = TransitionCallbackReturn.SUCCESS
FAIL = TransitionCallbackReturn.FAILURE


class Stub:
    """A localizer that records poses set on it and stays lost."""

    def __init__(self) -> None:
        self.poses: list[np.ndarray] = []
        self.reset = 0

    def update(self, odom, scan, image=None):  # type: ignore[no-untyped-def]
        return Estimate(Status.LOST, reason="stub")

    def set_pose(self, pose, cov):  # type: ignore[no-untyped-def]
        self.poses.append(np.asarray(pose))

    def reset_global(self) -> None:
        self.reset += 1


@pytest.fixture
def ctx() -> Iterator[Any]:
    import rclpy
    from rclpy.context import Context

    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    context = Context()
    rclpy.init(context=context, domain_id=random.randint(101, 200))
    yield context
    rclpy.shutdown(context=context)


@pytest.fixture
def map_yaml(tmp_path: Path) -> str:
    room = np.full((30, 30), 100, np.int8)
    room[1:-1, 1:-1] = 0  # walls around a free floor (a map with no wall is refused)
    save_map(OccupancyGrid(room, 0.1), tmp_path / "m.yaml")
    return str(tmp_path / "m.yaml")


def _node(
    ctx: Any, *files: Path, params: NodeParams | None = None, factory: Any = None
) -> LocalizationNode:
    args: list[str] = ["--ros-args"]
    for f in files:
        args += ["--params-file", str(f)]
    return LocalizationNode(
        context=ctx, cli_args=args if files else None, params=params, factory=factory
    )


def _extras(tmp_path: Path, **values: Any) -> Path:
    path = tmp_path / f"extras_{len(list(tmp_path.iterdir()))}.yaml"
    path.write_text(yaml.safe_dump({"amcl": {"ros__parameters": values}}))
    return path


@pytest.mark.parametrize("branch", ["humble", "jazzy", "kilted", "main"])
def test_nav2_files_of_every_branch_configure(ctx: Any, tmp_path: Path, branch: str) -> None:
    extras = _extras(tmp_path, odom_source="topic", laser_pose_source="parameters")
    node = _node(ctx, DATA / f"{branch}.yaml", extras)
    try:
        assert node.unknown_parameters() == []
        assert node.trigger_configure() == OK
        assert node.params is not None
        assert node.params.base_frame_id == "base_footprint"
        assert node.get_parameter("max_particles").value == 2000
        assert node.trigger_cleanup() == OK
    finally:
        node.destroy_node()


def test_an_unknown_parameter_is_warned_about_and_ignored(ctx: Any, tmp_path: Path) -> None:
    """nav2_amcl ignores names it does not declare (issue 27 item 6: `use_map_topic` from an
    older params file failed configure and so nav2's bring-up)."""
    bad = _extras(
        tmp_path,
        odom_source="topic",
        laser_pose_source="parameters",
        use_map_topic=True,
        alpah1=0.3,
        accept_map_updates=True,
    )
    node = _node(ctx, DATA / "main.yaml", bad)
    try:
        assert node.unknown_parameters() == ["alpah1", "use_map_topic"]
        assert node.trigger_configure() == OK
        assert node.core is not None
        assert node.params is not None
        assert node.params.amcl.alpha1 == 0.2  # main.yaml's value: the typo changed nothing
        assert node.trigger_cleanup() == OK
    finally:
        node.destroy_node()


def test_an_invalid_value_fails_configure(ctx: Any, tmp_path: Path) -> None:
    bad = _extras(tmp_path, odom_source="topic", laser_pose_source="parameters", z_hit=2.0)
    node = _node(ctx, bad)
    try:
        assert node.trigger_configure() == FAIL
    finally:
        node.destroy_node()


def test_runtime_changes_are_validated_and_rebuild_the_localizer(ctx: Any, map_yaml: str) -> None:
    built: list[NodeParams] = []

    def factory(grid: Any, p: NodeParams) -> Stub:
        built.append(p)
        return Stub()

    params = NodeParams(map_yaml=map_yaml, odom_source="topic", laser_pose_source="parameters")
    node = _node(ctx, params=params, factory=factory)
    try:
        node.autostart()
        assert node.active
        assert len(built) == 1
        res = node.set_parameters([Parameter("alpha1", value=0.35)])
        assert res[0].successful
        assert built[-1].amcl.alpha1 == 0.35
        assert node.params.amcl.alpha1 == 0.35
        res = node.set_parameters([Parameter("pf_z", value=1.5)])
        assert not res[0].successful
        assert "pf_z" in res[0].reason
        assert node.get_parameter("pf_z").value == pytest.approx(0.99)
        res = node.set_parameters([Parameter("localizer.converged_updates", value=5)])
        assert res[0].successful
        assert built[-1].localizer.converged_updates == 5
    finally:
        node.destroy_node()


def test_initial_pose_parameters_are_applied_at_activation(ctx: Any, map_yaml: str) -> None:
    stubs: list[Stub] = []
    params = NodeParams(
        map_yaml=map_yaml,
        odom_source="topic",
        laser_pose_source="parameters",
        set_initial_pose=True,
        initial_pose=(1.0, 2.0, 0.5),
    )
    node = _node(ctx, params=params, factory=lambda g, p: stubs.append(Stub()) or stubs[-1])
    try:
        assert node.trigger_configure() == OK
        assert stubs[-1].poses == []  # not before activation
        assert node.trigger_activate() == OK
        np.testing.assert_allclose(stubs[-1].poses[-1], [1.0, 2.0, 0.5])
    finally:
        node.destroy_node()


def test_saved_pose_file(ctx: Any, map_yaml: str, tmp_path: Path) -> None:
    path = tmp_path / "amcl_saved_pose"
    stubs: list[Stub] = []
    params = NodeParams(
        map_yaml=map_yaml,
        odom_source="topic",
        laser_pose_source="parameters",
        initialize_at_saved_pose=True,
        saved_pose_filepath=str(path),
    )
    node = _node(ctx, params=params, factory=lambda g, p: stubs.append(Stub()) or stubs[-1])
    try:
        assert node.trigger_configure() == OK
        assert node.trigger_activate() == FAIL  # no saved pose yet: nav2 fails activation too
        save_pose(path, [1.5, 0.5, 1.0], 12.5, "map")
        assert node.trigger_activate() == OK
        np.testing.assert_allclose(stubs[-1].poses[-1], [1.5, 0.5, 1.0])
    finally:
        node.destroy_node()


def test_saved_pose_format_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "pose"
    save_pose(path, [1.25, -2.5, math.pi / 3], 100.5, "map")
    text = path.read_text()
    assert "timestamp: 100.500000000" in text
    assert "frame_id: map" in text
    pose, frame = load_saved_pose(path)
    np.testing.assert_allclose(pose, [1.25, -2.5, math.pi / 3], atol=1e-6)
    assert frame == "map"
    path.write_text("x: one\n")
    with pytest.raises(ConfigurationError, match="saved_pose_filepath"):
        load_saved_pose(path)
    with pytest.raises(ConfigurationError, match="cannot read"):
        load_saved_pose(tmp_path / "missing")


def test_node_survives_a_crashing_localizer(ctx: Any, map_yaml: str) -> None:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    nav_msgs = pytest.importorskip("nav_msgs.msg")
    sensor_msgs = pytest.importorskip("sensor_msgs.msg")
    diagnostic_msgs = pytest.importorskip("diagnostic_msgs.msg")

    class Crashing:
        def update(self, odom, scan, image=None):  # type: ignore[no-untyped-def]
            raise RuntimeError("boom")

    params = NodeParams(
        map_yaml=map_yaml,
        sensor_qos="reliable",
        odom_source="topic",
        laser_pose_source="parameters",
        base_frame_id="base_link",
    )
    node = _node(ctx, params=params, factory=lambda g, p: Crashing())
    drv = rclpy.create_node("drv", context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    ex.add_node(drv)
    try:
        node.autostart()
        assert node.core is not None
        assert node.core.grid is not None
        assert node.core.grid.width == 30
        statuses: list[object] = []
        drv.create_subscription(
            diagnostic_msgs.DiagnosticArray, "symloc/status", statuses.append, 10
        )
        po = drv.create_publisher(nav_msgs.Odometry, "odom", 10)
        ps = drv.create_publisher(sensor_msgs.LaserScan, "scan", 10)
        scan = LaserScan(-math.pi, math.pi / 180, 0.1, 10.0, np.full(360, 2.0), stamp=1.0)
        end = time.monotonic() + 10
        rejected = "scan: rejected by the localizer"
        while (node.core.dropped[rejected] < 2 or len(statuses) < 2) and time.monotonic() < end:
            odom = odometry_to_fields(OdometryReading(np.zeros(3), 1.0))
            po.publish(build_rclpy(nav_msgs.Odometry, odom))
            ps.publish(build_rclpy(sensor_msgs.LaserScan, scan_to_fields(scan)))
            ex.spin_once(timeout_sec=0.1)
        assert node.core.dropped[rejected] >= 2  # counted, the node is still spinning
        # a status for every scan, saying the scan was not used and why
        values = {kv.key: kv.value for kv in statuses[-1].status[0].values}
        assert values["scan"] == "dropped"
        assert "RuntimeError: boom" in values["reason"]
        assert values["map_to_odom"] == "never sent (no pose earned yet)"
    finally:
        ex.shutdown()
        node.destroy_node()
        drv.destroy_node()


def test_the_example_of_symlocs_settings_configures_after_nav2s_file(
    ctx: Any, tmp_path: Path
) -> None:
    example = Path(__file__).parents[2] / "src/symloc/ros/examples/nav2_symloc_params.yaml"
    no_tf = _extras(tmp_path, odom_source="topic", laser_pose_source="parameters")
    node = _node(ctx, DATA / "main.yaml", example, no_tf)
    try:
        assert node.unknown_parameters() == []
        assert node.trigger_configure() == OK
        assert node.params is not None
        assert node.params.lidar_preset == "lds01"
        assert node.params.confidence.min_weight_share == 0.9
        assert node.params.claim.gate_sigmas == 4.0
    finally:
        node.destroy_node()


@pytest.mark.parametrize(
    "case",
    [
        "missing visual map",
        "visual map of a future schema",
        "garbage visual map",
        "garbage vocabulary",
    ],
)
def test_a_visual_map_or_vocabulary_that_cannot_be_used_fails_configure(
    ctx: Any, map_yaml: str, tmp_path: Path, case: str
) -> None:
    """As nav2 fails configure for a bad map (issue 31: the node activated and answered
    `lost: no map yet` forever); once the parameter names a good file, configure succeeds."""
    from test_ros_assemble import _bad_files

    from symloc.vision import VisualMap

    changes, _ = _bad_files(tmp_path)[case]
    base = {"map_yaml": map_yaml, "odom_source": "topic", "laser_pose_source": "parameters"}
    node = _node(ctx, params=NodeParams(**base, **changes))
    try:
        assert node.trigger_configure() == FAIL
        assert node.core is None
        good = tmp_path / "good.db"
        VisualMap(good, create=True).close()
        node.set_parameters(
            [Parameter("visual_map", value=str(good)), Parameter("vocabulary", value="")]
        )
        assert node.trigger_configure() == OK
        assert node.core is not None
        assert node.core.localizer is not None  # built on the map with the good visual map
        # a bad file named at run time is refused with the reason; the good one stays
        result = node.set_parameters([Parameter("visual_map", value=str(tmp_path / "nope.db"))])
        assert not result[0].successful
        assert "nope.db does not exist" in result[0].reason
        assert node.get_parameter("visual_map").value == str(good)
    finally:
        node.destroy_node()


def test_a_map_yaml_without_walls_fails_configure(ctx: Any, tmp_path: Path) -> None:
    blank = save_map(OccupancyGrid(np.zeros((30, 30), np.int8), 0.1), tmp_path / "blank")
    params = NodeParams(map_yaml=str(blank), odom_source="topic", laser_pose_source="parameters")
    node = _node(ctx, params=params)
    try:
        assert node.trigger_configure() == FAIL
    finally:
        node.destroy_node()
