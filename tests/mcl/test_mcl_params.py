from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.mcl import AmclParams

NAV2_YAML = """
amcl:
  ros__parameters:
    use_sim_time: True
    alpha1: 0.1
    alpha2: 0.2
    alpha3: 0.3
    alpha4: 0.4
    alpha5: 0.5
    base_frame_id: "base_footprint"
    beam_skip_distance: 0.5
    beam_skip_error_threshold: 0.9
    beam_skip_threshold: 0.3
    do_beamskip: false
    global_frame_id: "map"
    lambda_short: 0.1
    laser_likelihood_max_dist: 2.0
    laser_max_range: 100.0
    laser_min_range: -1.0
    laser_model_type: "likelihood_field"
    max_beams: 60
    max_particles: 2000
    min_particles: 500
    odom_frame_id: "odom"
    pf_err: 0.05
    pf_z: 0.99
    recovery_alpha_fast: 0.1
    recovery_alpha_slow: 0.001
    resample_interval: 1
    robot_model_type: "nav2_amcl::OmniMotionModel"
    save_pose_rate: 0.5
    sigma_hit: 0.2
    tf_broadcast: true
    transform_tolerance: 1.0
    update_min_a: 0.2
    update_min_d: 0.25
    z_hit: 0.5
    z_max: 0.05
    z_rand: 0.5
    z_short: 0.05
    scan_topic: scan
bt_navigator:
  ros__parameters:
    use_sim_time: True
"""


def test_defaults_are_nav2s():
    p = AmclParams()
    assert (p.alpha1, p.alpha5, p.max_particles, p.min_particles) == (0.2, 0.2, 2000, 500)
    assert (p.pf_err, p.pf_z, p.z_hit, p.z_rand, p.sigma_hit) == (0.05, 0.99, 0.5, 0.5, 0.2)
    assert (p.update_min_d, p.update_min_a, p.max_beams, p.resample_interval) == (0.25, 0.2, 60, 1)
    assert p.laser_model_type == "likelihood_field"
    assert p.motion_model == "diff-corrected"
    assert not p.recovery_enabled


def test_from_nav2_yaml_text_and_path(tmp_path):
    p = AmclParams.from_nav2_yaml(NAV2_YAML)
    assert p.alpha4 == 0.4
    assert p.motion_model == "omni-corrected"
    assert p.recovery_enabled
    assert p.ros_extras["base_frame_id"] == "base_footprint"
    f = tmp_path / "nav2_params.yaml"
    f.write_text(NAV2_YAML)
    assert AmclParams.from_nav2_yaml(f) == p
    assert AmclParams.from_nav2_yaml(str(f)) == p


def test_namespaced_block():
    text = "/**/amcl:\n  ros__parameters:\n    max_particles: 3000\n"
    assert AmclParams.from_nav2_yaml(text).max_particles == 3000


def test_replace_validates():
    p = AmclParams().replace(max_particles=100, min_particles=10)
    assert p.max_particles == 100
    with pytest.raises(ConfigurationError, match="unknown parameter"):
        AmclParams().replace(bogus=1)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"alpha1": -0.1}, "alpha1"),
        ({"z_hit": 1.5}, "z_hit"),
        ({"sigma_hit": 0.0}, "sigma_hit"),
        ({"min_particles": 3000}, "max_particles"),
        ({"pf_err": 0.0}, "pf_err"),
        ({"pf_z": 1.0}, "pf_z"),
        ({"pf_z": 2.33}, "pf_z"),
        ({"max_beams": 1}, "max_beams"),
        ({"resample_interval": 0}, "resample_interval"),
        ({"laser_model_type": "sonar"}, "laser_model_type"),
        ({"robot_model_type": "tank"}, "robot_model_type"),
        ({"recovery_alpha_slow": 0.2, "recovery_alpha_fast": 0.1}, "recovery_alpha_slow"),
        ({"update_min_d": -1.0}, "update_min_d"),
        ({"max_particles": 10.5}, "max_particles"),
        ({"do_beamskip": 0.5}, "do_beamskip"),
        ({"sigma_hit": float("nan")}, "sigma_hit"),
        ({"sigma_hit": "wide"}, "sigma_hit"),
        ({"laser_likelihood_max_dist": 0.0}, "laser_likelihood_max_dist"),
        ({"beam_skip_threshold": 2.0}, "beam_skip_threshold"),
        ({"hypothesis_min_weight": 0.0}, "hypothesis_min_weight"),
    ],
)
def test_out_of_range_raises(changes, match):
    with pytest.raises(ConfigurationError, match=match):
        AmclParams(**changes)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("amcl:\n  ros__parameters:\n    bogus_param: 1\n", "bogus_param"),
        ("controller_server:\n  ros__parameters: {}\n", "no 'amcl:' block"),
        ("amcl:\n  other: 1\n", "ros__parameters"),
        ("amcl: [unclosed\n", "not valid YAML"),
        ("- a\n- b\n", "mapping"),
        ("amcl:\n  ros__parameters:\n    alpha1: -1\n", "alpha1"),
    ],
)
def test_bad_yaml_raises(text, match):
    with pytest.raises(ConfigurationError, match=match):
        AmclParams.from_nav2_yaml(text)


def test_missing_file_raises(tmp_path):
    with pytest.raises(ConfigurationError, match="cannot read"):
        AmclParams.from_nav2_yaml(tmp_path / "absent.yaml")


@settings(max_examples=40, deadline=None)
@given(st.floats(-10, 10), st.floats(-10, 10))
def test_z_weights_validated(zh, zr):
    ok = 0 <= zh <= 1 and 0 <= zr <= 1 and zh + zr > 0
    if ok:
        assert AmclParams(z_hit=zh, z_rand=zr).z_hit == zh
    else:
        with pytest.raises(ConfigurationError, match="z_"):
            AmclParams(z_hit=zh, z_rand=zr)
