from __future__ import annotations

import numpy as np
import pytest

from symloc.errors import ConfigurationError, DataFormatError
from symloc.mcl.motion_model import sample_motion_model_odometry

N = 200_000


def _run(delta, alphas, model, start_theta=0.0, n=N, seed=0):
    rng = np.random.default_rng(seed)
    parts = np.tile([1.0, 2.0, start_theta], (n, 1))
    prev = np.array([0.0, 0.0, 0.0])
    return sample_motion_model_odometry(parts, prev, np.asarray(delta), alphas, rng, model=model)


def test_noise_free_motion_is_exact():
    out = _run([0.5, 0.0, 0.3], (0, 0, 0, 0, 0), "diff-corrected", start_theta=np.pi / 2, n=5)
    np.testing.assert_allclose(out, np.tile([1.0, 2.5, np.pi / 2 + 0.3], (5, 1)), atol=1e-12)
    out = _run([0.5, 0.2, 0.3], (0, 0, 0, 0, 0), "omni-corrected", start_theta=np.pi / 2, n=5)
    np.testing.assert_allclose(out, np.tile([0.8, 2.5, np.pi / 2 + 0.3], (5, 1)), atol=1e-12)


@pytest.mark.parametrize(
    ("model", "std"), [("diff-corrected", np.sqrt(0.1) * 0.8), ("diff", 0.1 * 0.64)]
)
def test_translation_noise_moments(model, std):
    # forward 0.8 m, only alpha3: trans_hat ~ N(0.8, std^2) along x
    out = _run([0.8, 0.0, 0.0], (0, 0, 0.1, 0, 0), model)
    dx = out[:, 0] - 1.0
    assert dx.mean() == pytest.approx(0.8, abs=4 * std / np.sqrt(N))
    assert dx.std() == pytest.approx(std, rel=0.01)
    np.testing.assert_allclose(out[:, 2], 0.0, atol=1e-12)


@pytest.mark.parametrize(
    ("model", "var"), [("diff-corrected", 0.2 * 0.5**2), ("diff", (0.2 * 0.5**2) ** 2)]
)
def test_rotation_noise_moments(model, var):
    # pure rotation 0.5 rad, only alpha1: rot1 = 0, so theta ~ N(0.5, var)
    out = _run([0.0, 0.0, 0.5], (0.2, 0, 0, 0, 0), model)
    assert out[:, 2].mean() == pytest.approx(0.5, abs=4 * np.sqrt(var / N))
    assert out[:, 2].var() == pytest.approx(var, rel=0.02)


def test_rotation_from_translation_alpha2():
    # forward 1 m, only alpha2: rot1_hat and rot2_hat each N(0, alpha2 * 1): theta var = 2*alpha2
    out = _run([1.0, 0.0, 0.0], (0, 0.01, 0, 0, 0), "diff-corrected")
    assert out[:, 2].var() == pytest.approx(0.02, rel=0.02)
    # lateral spread from rot1 alone: y = sin(rot1_hat) ~ N(0, 0.01)
    assert (out[:, 1] - 2.0).var() == pytest.approx(0.01, rel=0.03)


def test_backward_motion_treated_like_forward():
    fwd = _run([0.5, 0.0, 0.0], (0.3, 0, 0, 0, 0), "diff-corrected")
    back = _run([-0.5, 0.0, 0.0], (0.3, 0, 0, 0, 0), "diff-corrected")
    # rot1 = pi for the backward move, but the noise uses min(|rot|, |pi - rot|) = 0
    assert fwd[:, 2].std() == pytest.approx(0.0, abs=1e-12)
    assert back[:, 2].std() == pytest.approx(0.0, abs=1e-9)
    assert back[:, 0].mean() == pytest.approx(0.5, abs=1e-9)


@pytest.mark.parametrize(
    ("model", "std"), [("omni-corrected", np.sqrt(0.05) * 0.6), ("omni", 0.05 * 0.36)]
)
def test_omni_strafe_moments(model, std):
    out = _run([0.6, 0.0, 0.0], (0, 0, 0, 0, 0.05), model)
    assert (out[:, 1] - 2.0).std() == pytest.approx(std, rel=0.01)
    assert (out[:, 0] - 1.0).std() == pytest.approx(0.0, abs=1e-12)


def test_omni_rotation_moments():
    out = _run([0.0, 0.0, 0.4], (0, 0, 0, 0.3, 0), "omni-corrected")
    assert out[:, 2].var() == pytest.approx(0.3 * 0.16, rel=0.02)


def test_theta_wrapped():
    out = _run([0.0, 0.0, 0.5], (0.2, 0, 0, 0, 0), "diff-corrected", start_theta=3.0, n=1000)
    assert np.all(out[:, 2] <= np.pi)
    assert np.all(out[:, 2] > -np.pi)


def test_errors():
    rng = np.random.default_rng(0)
    p = np.zeros((3, 3))
    with pytest.raises(ConfigurationError, match="model"):
        sample_motion_model_odometry(p, np.zeros(3), np.ones(3), (0.1,) * 5, rng, model="tank")
    with pytest.raises(ConfigurationError, match="alphas"):
        sample_motion_model_odometry(p, np.zeros(3), np.ones(3), (-0.1,) * 5, rng)
    with pytest.raises(ConfigurationError, match="particles"):
        sample_motion_model_odometry(np.zeros(3), np.zeros(3), np.ones(3), (0.1,) * 5, rng)
    with pytest.raises(DataFormatError, match="finite"):
        sample_motion_model_odometry(p, np.zeros(3), np.array([np.nan, 0, 0]), (0.1,) * 5, rng)
