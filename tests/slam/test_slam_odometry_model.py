"""The odometry model learns calibration and noise from the run (symloc.slam.odometry_model)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.sim.odometry_noise import OdometryRegime, regime_odometry
from symloc.slam import OdometryModel, OdometryModelParams


def _wander(n: int, rng: np.random.Generator) -> np.ndarray:
    poses = [np.zeros(3)]
    for _ in range(n - 1):
        p = poses[-1]
        d, turn = rng.uniform(0.2, 0.6), rng.normal(0.0, 0.4)
        poses.append(np.array([p[0] + d * math.cos(p[2]), p[1] + d * math.sin(p[2]), p[2] + turn]))
    return np.array(poses)


def test_learns_the_calibration_and_a_noise_level_from_matched_nodes() -> None:
    rng = np.random.default_rng(0)
    truth = _wander(300, rng)
    regime = OdometryRegime("cal", (0.0016, 0.0001, 0.0004, 0.0001), 1.015, 0.99)
    odom = regime_odometry(truth, regime, 1)
    model = OdometryModel()
    assert not model.fitted
    prior_st, _ = model.sigmas(np.array([0.5, 0.0, 0.0]))
    for k in range(truth.shape[0]):
        match = truth[k] + np.array([*rng.normal(0, 0.01, 2), rng.normal(0, 0.002)])
        model.add_node(odom[k], match)
    assert model.fitted
    assert model.trans_scale == pytest.approx(1 / 1.015, abs=0.004)
    assert model.rot_scale == pytest.approx(1 / 0.99, abs=0.006)
    st, _ = model.sigmas(np.array([0.5, 0.0, 0.0]))
    assert st < 0.5 * prior_st  # it learnt that this odometry is good
    corrected = model.correct(np.array([1.015, 0.0, 0.0]))
    assert corrected[0] == pytest.approx(1.0, abs=0.005)
    summary = model.summary()
    assert summary["matched_nodes"] == 300


def test_unmatched_nodes_teach_nothing_and_params_validate() -> None:
    model = OdometryModel(OdometryModelParams(min_pairs=5))
    for k in range(20):
        model.add_node(np.array([0.1 * k, 0.0, 0.0]), None)
    assert not model.fitted
    with pytest.raises(ConfigurationError, match="max_lag: expected an integer >= 1"):
        OdometryModelParams(max_lag=0)
