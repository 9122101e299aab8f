"""nav2's params files as the node's ROS parameters (symloc.ros.nav2_params)."""

from __future__ import annotations

from pathlib import Path

import pytest

from symloc.errors import ConfigurationError
from symloc.ros.nav2_params import (
    WITHOUT_EFFECT,
    node_params_from_ros,
    parameter_defaults,
    read_params_block,
    ros_values,
    seeded_from_time,
)
from symloc.ros.params import NodeParams

DATA = Path(__file__).parent / "data" / "nav2"

#: Every parameter nav2_amcl declares on nav2's humble, jazzy, kilted and main branches
#: (amcl_node.cpp) and nav2's lifecycle node base, plus the names their nav2_params.yaml use.
NAV2_NAMES = [
    "alpha1",
    "alpha2",
    "alpha3",
    "alpha4",
    "alpha5",
    "always_reset_initial_pose",
    "base_frame_id",
    "beam_skip_distance",
    "beam_skip_error_threshold",
    "beam_skip_threshold",
    "do_beamskip",
    "first_map_only",
    "freespace_downsampling",
    "global_frame_id",
    "initial_pose.x",
    "initial_pose.y",
    "initial_pose.yaw",
    "initial_pose.z",
    "initialize_at_saved_pose",
    "lambda_short",
    "laser_likelihood_max_dist",
    "laser_max_range",
    "laser_min_range",
    "laser_model_type",
    "map_topic",
    "max_beams",
    "max_particles",
    "min_particles",
    "odom_frame_id",
    "pf_err",
    "pf_z",
    "random_seed",
    "recovery_alpha_fast",
    "recovery_alpha_slow",
    "resample_interval",
    "robot_model_type",
    "save_pose_rate",
    "saved_pose_filepath",
    "scan_topic",
    "set_initial_pose",
    "sigma_hit",
    "tf_broadcast",
    "transform_tolerance",
    "update_min_a",
    "update_min_d",
    "z_hit",
    "z_max",
    "z_rand",
    "z_short",
    "allow_parameter_qos_overrides",
    "introspection_mode",
    "service_introspection_mode",
    "use_sim_time",
    "bond_heartbeat_period",
    "autostart_node",
    "bond_disable_heartbeat_timeout",
]


@pytest.mark.parametrize("branch", ["humble", "jazzy", "kilted", "main"])
def test_nav2_params_file_of_each_branch(branch: str) -> None:
    values = read_params_block(DATA / f"{branch}.yaml")
    params = node_params_from_ros(values)
    assert params.base_frame_id == "base_footprint"
    assert params.global_frame_id == "map"
    assert params.odom_frame_id == "odom"
    assert params.amcl.max_particles == 2000
    assert params.amcl.min_particles == 500
    assert params.amcl.laser_model_type == "likelihood_field"
    assert params.amcl.robot_model_type == "nav2_amcl::DifferentialMotionModel"
    assert params.transform_tolerance == 1.0
    assert params.tf_broadcast
    if values.get("random_seed", 0) < 0:  # nav2's -1: a time seed, unless symloc's seed
        assert seeded_from_time(values)
        assert node_params_from_ros({**values, "seed": 5}).seed == 5
    else:  # humble's file has no random_seed (nav2_amcl seeds from the time as well)
        assert params.seed == 0


def test_every_nav2_name_is_declared_and_accepted() -> None:
    declared = parameter_defaults()
    missing = [n for n in NAV2_NAMES if n not in declared and n != "use_sim_time"]
    assert missing == []
    values = dict(declared)
    params = node_params_from_ros(values)  # nav2's defaults throughout
    assert params.base_frame_id == "base_footprint"
    assert params.save_pose_rate == 0.5
    assert params.saved_pose_filepath == "/tmp/amcl_saved_pose"
    for name in WITHOUT_EFFECT:
        assert name in declared


def test_nav2_names_map_to_their_settings() -> None:
    values = {
        "alpha1": 0.3,
        "max_particles": 3000,
        "random_seed": 7,
        "initial_pose.x": 1.0,
        "initial_pose.y": -2.0,
        "initial_pose.z": 0.5,
        "initial_pose.yaw": 0.25,
        "set_initial_pose": True,
        "first_map_only": True,
        "tf_broadcast": False,
        "freespace_downsampling": True,
        "localizer.converged_updates": 4,
        "symmetry.min_points": 40,
        "laser_pose": [0.2, 0.0, 3.0],
    }
    p = node_params_from_ros(values)
    assert p.amcl.alpha1 == 0.3
    assert p.amcl.max_particles == 3000
    assert p.seed == 7
    assert p.initial_pose == (1.0, -2.0, 0.25)
    assert p.set_initial_pose
    assert p.first_map_only
    assert not p.tf_broadcast
    assert p.localizer.converged_updates == 4
    assert p.symmetry == {"min_points": 40}
    assert p.laser_pose == (0.2, 0.0, 3.0)


def test_random_seed_below_zero_seeds_from_the_time() -> None:
    seeds = {node_params_from_ros({"random_seed": -1}).seed for _ in range(3)}
    assert all(0 <= s < 2**31 for s in seeds)
    assert seeded_from_time({"random_seed": -1, "seed": None})
    assert not seeded_from_time({"random_seed": -1, "seed": 3})
    assert node_params_from_ros({"random_seed": -1, "seed": 3}).seed == 3
    assert node_params_from_ros({}).seed == 0  # nothing said: symloc's reproducible default


def test_unknown_names_are_reported_and_ignored_when_asked() -> None:
    heard: list[str] = []
    p = node_params_from_ros({"use_map_topic": True, "alpha1": 0.3}, on_unknown=heard.append)
    assert p.amcl.alpha1 == 0.3
    assert len(heard) == 1
    assert "'use_map_topic': unknown to symloc" in heard[0]
    assert "ignored" in heard[0]


def test_symloc_settings_round_trip_through_ros_values() -> None:
    p = NodeParams(
        visual_map="/data/places.db",
        camera_intrinsics=(500.0, 500.0, 320.0, 240.0),
        laser_pose=(0.1, 0.0, 0.0),
        odom_source="topic",
        symmetry={"min_points": 30},
    )
    back = node_params_from_ros(ros_values(p))
    assert back == p


@pytest.mark.parametrize(
    ("values", "match"),
    [
        ({"alpah1": 0.2}, "'alpah1': unknown to symloc"),
        ({"localizer.nope": 1}, "not a LocalizerConfig field"),
        ({"symmetry.nope": 1}, "not a SymmetryConfig field"),
        ({"z_hit": 1.5}, "z_hit"),
        ({"random_seed": "x"}, "random_seed"),
        ({"odom_source": "wheel"}, "odom_source"),
        ({"laser_pose": [1.0, 2.0]}, "laser_pose"),
        ({"alpha1": 0.2, "amcl.alpha1": 0.3}, "also given"),
    ],
)
def test_bad_parameters_are_named(values: dict, match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        node_params_from_ros(values)


def test_read_params_block_merges_wildcards_and_namespaces(tmp_path: Path) -> None:
    path = tmp_path / "p.yaml"
    path.write_text(
        "/**:\n  ros__parameters:\n    use_sim_time: true\n    alpha1: 0.1\n"
        "robot1/amcl:\n  ros__parameters:\n    alpha1: 0.4\n    initial_pose: {x: 1.0, yaw: 0.5}\n"
        "map_server:\n  ros__parameters:\n    yaml_filename: m.yaml\n"
    )
    values = read_params_block(path)
    assert values == {
        "use_sim_time": True,
        "alpha1": 0.4,
        "initial_pose.x": 1.0,
        "initial_pose.yaw": 0.5,
    }
    assert read_params_block(path, "controller") == {"use_sim_time": True, "alpha1": 0.1}
    only = tmp_path / "q.yaml"
    only.write_text("map_server:\n  ros__parameters:\n    yaml_filename: m.yaml\n")
    with pytest.raises(ConfigurationError, match="no block for node 'amcl'"):
        read_params_block(only)
