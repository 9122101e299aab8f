"""Odometry regimes (symloc.sim.odometry_noise): seeded, calibrated, documented figures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.geometry import relative
from symloc.sim.odometry_noise import (
    HEAVY,
    ODOMETRY_REGIMES,
    REALISTIC,
    OdometryRegime,
    increment_errors,
    regime_odometry,
)


def _square_drive(n_side: int = 20) -> np.ndarray:
    """A 4 m x 4 m square driven once: straight legs of 0.2 m steps, 90 deg turns on the spot."""
    poses = [np.array([0.0, 0.0, 0.0])]
    for _ in range(4):
        for _ in range(n_side):
            p = poses[-1]
            poses.append(p + np.array([0.2 * math.cos(p[2]), 0.2 * math.sin(p[2]), 0.0]))
        poses.append(poses[-1] + np.array([0.0, 0.0, math.pi / 2]))
    return np.array(poses)


@pytest.mark.parametrize("name", ["realistic", "heavy"])
def test_regimes_are_reproducible_with_seeds(name: str) -> None:
    ref = _square_drive()
    a = regime_odometry(ref, name, 7)
    b = regime_odometry(ref, ODOMETRY_REGIMES[name], np.random.default_rng(7))
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, regime_odometry(ref, name, 8))
    np.testing.assert_allclose(a[0], ref[0])


def test_calibration_scales_distance_and_rotation_exactly_without_noise() -> None:
    ref = _square_drive()
    quiet = OdometryRegime("cal", (0.0, 0.0, 0.0, 0.0), trans_scale=1.015, rot_scale=0.99)
    odo = regime_odometry(ref, quiet, 0)
    d_ref = relative(ref[:-1], ref[1:])
    d_odo = relative(odo[:-1], odo[1:])
    moving = np.hypot(d_ref[:, 0], d_ref[:, 1]) > 0.1
    np.testing.assert_allclose(
        np.hypot(d_odo[moving, 0], d_odo[moving, 1]),
        1.015 * np.hypot(d_ref[moving, 0], d_ref[moving, 1]),
    )
    np.testing.assert_allclose(d_odo[:, 2], 0.99 * d_ref[:, 2], atol=1e-12)


def test_realistic_is_far_below_heavy_per_scan() -> None:
    ref = _square_drive(40)
    real = increment_errors(ref, regime_odometry(ref, REALISTIC, 1))
    heavy = increment_errors(ref, regime_odometry(ref, HEAVY, 1))
    assert real["trans_median_m"] < 0.35 * heavy["trans_median_m"]
    assert real["rot_p90_deg"] < 0.3 * heavy["rot_p90_deg"]
    # 0.2 m steps: 2 % noise + 1.5 % bias is a few millimetres, heading ~0.1-0.3 deg
    assert 0.002 < real["trans_median_m"] < 0.01


def test_regime_validation_and_unknown_names() -> None:
    with pytest.raises(ConfigurationError, match="odometry regime: expected one of"):
        regime_odometry(_square_drive(), "perfect", 0)
    with pytest.raises(
        ConfigurationError, match=r"OdometryRegime\.trans_scale: expected a value > 0"
    ):
        OdometryRegime("x", (0, 0, 0, 0), trans_scale=0.0)
    with pytest.raises(ConfigurationError, match=r"OdometryRegime.alphas\[2\]"):
        OdometryRegime("x", (0, 0, -1, 0))
    assert "x 1.015" in REALISTIC.describe()
    assert "no calibration error" in HEAVY.describe()
