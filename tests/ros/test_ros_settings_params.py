"""The localizer's settings tree and the ROS parameters: every leaf a parameter and back.

(a) Every leaf of :class:`~symloc.localizer.settings.LocalizerSettings`, set to a value other
than its default, survives settings -> ROS parameter values -> settings. (b) Every parameter
the node declares changes what it builds (a settings leaf) or how it runs (a node field), and
together the declared parameters reach every leaf of the tree. Leaves and parameters are read
from the dataclasses, so a field added to a block is covered without a change here.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import pytest

from symloc.errors import ConfigurationError
from symloc.localizer.settings import (
    LocalizerSettings,
    leaf_paths,
    leaf_values,
    settings_from_leaves,
)
from symloc.mcl.params import LASER_MODELS, MOTION_MODELS
from symloc.ros.nav2_params import (
    WITHOUT_EFFECT,
    node_params_from_ros,
    parameter_defaults,
    settings_from_ros,
    settings_to_ros,
)
from symloc.ros.params import ALIASES, NOT_PARAMETERS, NodeParams
from symloc.symmetry import SymmetryConfig

#: Other values for the string settings and node fields (tried in order).
STRINGS: dict[str, tuple[Any, ...]] = {
    "laser_model_type": tuple(LASER_MODELS),
    "robot_model_type": tuple(MOTION_MODELS),
    "mode": ("build_visual_map",),
    "lidar_preset": ("lds01",),
    "laser_pose_source": ("parameters",),
    "odom_source": ("topic",),
    "sensor_qos": ("reliable",),
    "camera_intrinsics": ([500.0, 501.0, 320.0, 240.0],),
    "camera_dist_coeffs": ([0.1, 0.0, 0.0, 0.0],),
}


def _candidates(name: str, default: Any) -> list[Any]:
    """Values other than ``default`` to try for a leaf or parameter called ``name``."""
    short = name.rpartition(".")[2]
    if short in STRINGS:
        return [v for v in STRINGS[short] if v != default]
    if default is None and name == "seed":  # declared not set: nav2's random_seed decides
        return [7]
    if default is None and name.startswith("symmetry."):
        default = getattr(SymmetryConfig(), short)
        if default is None:
            return [0.02, 0.5]
    if isinstance(default, bool):
        return [not default]
    if isinstance(default, int):
        return [default + 1, default - 1, 3]
    if isinstance(default, float):
        if default == 0.0:
            return [0.01, 0.5, -0.01]
        return [default * 1.1, default * 0.9, default + 0.5, default * 0.5]
    if isinstance(default, (tuple, list)):
        return [[float(v) * 1.1 + 0.01 for v in default]]
    if isinstance(default, str):
        return [default + "_other" if default else "/tmp/symloc_other"]
    raise AssertionError(f"{name}: no candidate value for {default!r}")


def _settings_leaves() -> list[str]:
    return [p for p in leaf_paths() if p not in NOT_PARAMETERS]


@pytest.mark.parametrize("path", _settings_leaves())
def test_every_settings_leaf_round_trips_through_ros_parameters(path: str) -> None:
    default = leaf_values(LocalizerSettings())[path]
    for value in _candidates(path, default):
        try:
            settings = settings_from_leaves({path: value})
        except ConfigurationError:
            continue
        break
    else:
        pytest.fail(f"{path}: no valid value other than {default!r}")
    assert leaf_values(settings)[path] != default
    values = settings_to_ros(settings)
    back = settings_from_ros(values)
    assert back == settings
    assert leaf_values(back)[path] == leaf_values(settings)[path]


def test_a_bench_like_tree_round_trips_whole() -> None:
    from symloc.lidar_spec import RPLIDAR_A2
    from symloc.localizer import LocalizerConfig
    from symloc.localizer.claim import ClaimConfig
    from symloc.mcl import AmclParams
    from symloc.mcl.confidence import ConfidenceConfig

    settings = LocalizerSettings(
        amcl=AmclParams(max_particles=5000, alpha1=0.01, laser_model_type="beam"),
        confidence=ConfidenceConfig(min_weight_share=0.8, rival_check=False),
        claim=ClaimConfig(gate_sigmas=3.0, odometry_alphas=(0.1, 0.2, 0.3, 0.4)),
        localizer=LocalizerConfig(allow_mapping=True, flip_patience=7),
        symmetry=SymmetryConfig.from_lidar(RPLIDAR_A2),
        laser_pose=(0.2, -0.1, math.pi),
        seed=42,
    )
    params = node_params_from_ros(settings_to_ros(settings))
    assert params.mode == "build_visual_map"
    assert params.settings() == settings


def test_mode_sets_allow_mapping_and_localizer_allow_mapping_is_refused() -> None:
    assert node_params_from_ros({"mode": "build_visual_map"}).settings().localizer.allow_mapping
    assert not NodeParams().settings().localizer.allow_mapping
    with pytest.raises(ConfigurationError, match="set by 'mode'"):
        node_params_from_ros({"localizer.allow_mapping": True})
    with pytest.raises(ConfigurationError, match="set by 'mode'"):
        NodeParams.from_dict({"localizer": {"allow_mapping": True}})


def test_older_converged_names_set_the_confidence_judgement() -> None:
    for alias, target in ALIASES.items():
        block, _, name = target.partition(".")
        value = getattr(getattr(LocalizerSettings(), block), name) * 0.95
        got = node_params_from_ros({alias: value}).settings()
        assert getattr(got.confidence, name) == value
        yaml_block = {"localizer": {alias.partition(".")[2]: value}}
        assert getattr(NodeParams.from_dict(yaml_block).confidence, name) == value
        with pytest.raises(ConfigurationError, match="older name"):
            node_params_from_ros({alias: value, target: value * 0.9})
        # as the lifecycle node reads them: every declared parameter has a value
        declared = {**parameter_defaults(), alias: value}
        assert getattr(node_params_from_ros(declared).confidence, name) == value


def test_confidence_and_claim_blocks_from_yaml() -> None:
    text = """
symloc:
  ros__parameters:
    confidence: {min_weight_share: 0.8, hold_updates: 5}
    claim: {gate_sigmas: 3.0, odometry_alphas: [0.01, 0.02, 0.03, 0.04]}
"""
    settings = NodeParams.from_yaml(text).settings()
    assert settings.confidence.min_weight_share == 0.8
    assert settings.confidence.hold_updates == 5
    assert settings.claim.gate_sigmas == 3.0
    assert settings.claim.odometry_alphas == (0.01, 0.02, 0.03, 0.04)
    with pytest.raises(ConfigurationError, match=r"claim\.nope"):
        NodeParams.from_dict({"claim": {"nope": 1}})
    with pytest.raises(ConfigurationError, match=r"ClaimConfig\.gate_sigmas"):
        node_params_from_ros({"claim.gate_sigmas": -1.0})
    with pytest.raises(ConfigurationError, match=r"ConfidenceConfig\.min_weight_share"):
        node_params_from_ros({"confidence.min_weight_share": 0.2})


def _declared() -> list[str]:
    return [n for n in parameter_defaults() if n not in WITHOUT_EFFECT and n not in ALIASES]


@pytest.mark.parametrize("name", _declared())
def test_every_declared_parameter_changes_the_build_or_the_node(name: str) -> None:
    default = parameter_defaults()[name]
    base = node_params_from_ros({})
    for value in _candidates(name, default):
        if name == "random_seed":
            value = 7
        try:
            params = node_params_from_ros({name: value})
        except ConfigurationError:
            continue
        break
    else:
        pytest.fail(f"{name}: no valid value other than {default!r}")
    assert params != base or params.settings() != base.settings(), name


def test_the_declared_parameters_reach_every_settings_leaf() -> None:
    base = leaf_values(node_params_from_ros({}).settings())
    reached: set[str] = set()
    for name in _declared():
        default = parameter_defaults()[name]
        for value in _candidates(name, default):
            try:
                got = leaf_values(node_params_from_ros({name: value}).settings())
            except ConfigurationError:
                continue
            reached |= {p for p in got if got[p] != base[p]}
            break
    missing = set(leaf_paths()) - reached - (NOT_PARAMETERS - {"localizer.allow_mapping"})
    assert not missing, sorted(missing)


def test_settings_validate_and_name_the_field() -> None:
    with pytest.raises(ConfigurationError, match="laser_pose"):
        LocalizerSettings(laser_pose=(0.0, 1.0))  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="seed"):
        LocalizerSettings(seed=-1)
    with pytest.raises(ConfigurationError, match="claim"):
        LocalizerSettings(claim={})  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match=r"claim\.nope"):
        settings_from_leaves({"claim.nope": 1})
    with pytest.raises(ConfigurationError, match=r"ClaimConfig\.patience"):
        LocalizerSettings().replace(**{"claim.patience": 0})
    assert dataclasses.replace(LocalizerSettings(), seed=3).seed == 3


def test_a_bad_field_in_a_params_file_names_the_file_and_the_field(tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "robot.yaml"
    path.write_text(
        "symloc:\n  ros__parameters:\n    claim:\n      local_window: [0.5]\n", encoding="utf-8"
    )
    with pytest.raises(ConfigurationError, match=r"robot\.yaml: ClaimConfig\.local_window"):
        NodeParams.from_yaml(path)
    path.write_text("symloc:\n  ros__parameters:\n    claim:\n      local_window: [0.5, 0.3]\n")
    assert NodeParams.from_yaml(path).claim.local_window == (0.5, 0.3)
