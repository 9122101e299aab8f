"""ATE / RPE as evo defines them (symloc.bench.slam_metrics)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.bench.slam_metrics import (
    ate,
    field_coverage,
    rpe,
    similarity_residuals,
    umeyama_se2,
    umeyama_se2_at,
    umeyama_sim2,
)
from symloc.errors import ConfigurationError
from symloc.geometry import compose
from symloc.grid.map_error_field import MapErrorField


def _traj(n: int = 30) -> np.ndarray:
    t = np.linspace(0, 6, n)
    return np.column_stack([np.cos(t) * 3, np.sin(2 * t), t * 0.7])


@settings(max_examples=25, deadline=None)
@given(x=st.floats(-50, 50), y=st.floats(-50, 50), th=st.floats(-3.1, 3.1))
def test_ate_is_zero_for_a_rigidly_moved_copy(x: float, y: float, th: float) -> None:
    ref = _traj()
    est = compose(np.array([x, y, th]), ref)
    res = ate(ref, est)
    assert res.rmse < 1e-9
    assert ate(ref, est, align=False).rmse == pytest.approx(
        np.sqrt(np.mean(np.sum((est[:, :2] - ref[:, :2]) ** 2, axis=1)))
    )


def test_ate_known_value_for_constant_lateral_noise() -> None:
    ref = _traj(40)
    est = ref.copy()
    est[::2, 0] += 0.1
    est[1::2, 0] -= 0.1  # zero-mean: alignment cannot remove it
    res = ate(ref, est)
    assert res.rmse == pytest.approx(0.1, abs=2e-3)
    assert res.max >= res.median >= res.min
    assert res.errors.shape == (40,)


def test_umeyama_recovers_transform() -> None:
    rng = np.random.default_rng(0)
    src = rng.normal(size=(20, 2))
    pose = np.array([1.0, -2.0, 0.7])
    c, s = np.cos(0.7), np.sin(0.7)
    dst = src @ np.array([[c, s], [-s, c]]) + pose[:2]
    np.testing.assert_allclose(umeyama_se2(src, dst), pose, atol=1e-12)


def test_rpe_matches_hand_computed_example() -> None:
    ref = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    est = np.array([[0.0, 0, 0], [1, 0.1, 0], [2, 0.1, 0.2]])
    r = rpe(ref, est)
    # pair 0-1: translation error 0.1, rotation 0; pair 1-2: translation 0, rotation 0.2
    assert r.n_pairs == 2
    assert r.trans_rmse == pytest.approx(np.sqrt((0.1**2 + 0.0) / 2))
    assert r.rot_rmse == pytest.approx(np.sqrt((0 + 0.2**2) / 2))
    r2 = rpe(ref, est, delta=2)
    assert r2.n_pairs == 1
    assert r2.trans_rmse == pytest.approx(0.1)


def test_rpe_zero_for_rigid_copy() -> None:
    ref = _traj()
    est = compose(np.array([3.0, 1.0, 2.0]), ref)
    assert rpe(ref, est).trans_rmse < 1e-9


def test_errors() -> None:
    with pytest.raises(ConfigurationError, match="estimate: expected as many poses"):
        ate(_traj(5), _traj(6))
    with pytest.raises(ConfigurationError, match="delta: expected an integer >= 1"):
        rpe(_traj(5), _traj(5), delta=0)
    with pytest.raises(ConfigurationError, match="expected more than delta=10 poses"):
        rpe(_traj(5), _traj(5), delta=10)
    with pytest.raises(ConfigurationError, match="reference: expected shape"):
        ate(np.zeros((4, 2)), np.zeros((4, 2)))


def test_umeyama_sim2_recovers_a_scaled_rigid_motion() -> None:
    rng = np.random.default_rng(3)
    src = rng.uniform(-4.0, 4.0, size=(40, 2))
    pose = np.array([0.7, -1.2, 0.4])
    c, s = np.cos(pose[2]), np.sin(pose[2])
    dst = 1.0075 * src @ np.array([[c, -s], [s, c]]).T + pose[:2]
    got, scale = umeyama_sim2(src, dst)
    np.testing.assert_allclose(got, pose, atol=1e-12)
    assert scale == pytest.approx(1.0075, abs=1e-12)
    # the rigid alignment cannot take the 0.75 % out: it leaves centimetres at 4 m
    rigid = umeyama_se2(src, dst)
    cr, sr = np.cos(rigid[2]), np.sin(rigid[2])
    left = dst - (src @ np.array([[cr, -sr], [sr, cr]]).T + rigid[:2])
    assert np.max(np.hypot(*left.T)) > 0.01


def test_umeyama_se2_at_is_right_at_its_anchor_and_off_by_the_scale_elsewhere() -> None:
    rng = np.random.default_rng(4)
    # a lap on one side of the room: its centroid is not the room's middle
    src = rng.uniform(0.5, 4.0, size=(60, 2))
    pose = np.array([0.3, 0.2, -0.6])
    c, s = np.cos(pose[2]), np.sin(pose[2])
    rot = np.array([[c, -s], [s, c]])
    dst = 0.95 * src @ rot.T + pose[:2]  # a map 5 % short
    middle_src = np.array([-1.0, 0.5])
    middle = 0.95 * rot @ middle_src + pose[:2]
    got = umeyama_se2_at(src, dst, middle)
    assert got[2] == pytest.approx(pose[2], abs=1e-12)
    np.testing.assert_allclose(compose(got, np.array([*middle_src, 0.0]))[:2], middle, atol=1e-12)
    # 2 m from the middle the truth frame is off by the scale error times 2 m
    far = np.array([middle_src[0] + 2.0, middle_src[1], 0.0])
    off = compose(got, far)[:2] - (0.95 * rot @ far[:2] + pose[:2])
    assert np.hypot(*off) == pytest.approx(0.05 * 2.0, abs=1e-9)
    # the plain rigid fit is right at the lap's centroid instead, not at the middle
    plain = umeyama_se2(src, dst)
    assert np.hypot(*(compose(plain, np.array([*middle_src, 0.0]))[:2] - middle)) > 0.1
    # without a scale error both are the same frame
    exact = src @ rot.T + pose[:2]
    np.testing.assert_allclose(
        umeyama_se2_at(src, exact, middle), umeyama_se2(src, exact), atol=1e-9
    )


def test_similarity_residuals_leave_the_distortion_and_not_the_scale() -> None:
    """A trip drawn 1 % too large, turned and moved, leaves nothing once its scale is fitted;
    one point bent by 5 cm leaves (nearly) that point's bend."""
    truth = _traj(40)[:, :2]
    c, s = np.cos(0.4), np.sin(0.4)
    slam = 1.01 * truth @ np.array([[c, -s], [s, c]]).T + [2.0, -1.0]
    res, scale = similarity_residuals(truth, slam)
    assert res.shape == (40, 2)
    assert scale == pytest.approx(1.01, abs=1e-9)
    assert np.abs(res).max() < 1e-9
    bent = slam.copy()
    bent[7] += [0.05, 0.0]
    res, _ = similarity_residuals(truth, bent)
    assert int(np.argmax(np.hypot(*res.T))) == 7
    assert np.hypot(*res[7]) == pytest.approx(0.05, abs=0.005)


def test_field_coverage_counts_errors_inside_each_places_95_percent_ellipse() -> None:
    """Two places, 1 cm and 10 cm std along x (1 cm along y): an error of 2 std along x is
    inside (2.45 std is the 95 % radius), 3 std is not; raising the floor to 10 cm takes in the
    first place's large error too."""
    field = MapErrorField(
        np.array([[0.0, 0.0], [10.0, 0.0]]),
        np.array([np.diag([1e-4, 1e-4]), np.diag([1e-2, 1e-4])]),
    )
    xy = np.array([[0.1, 0.0], [0.2, 0.0], [9.9, 0.0], [10.1, 0.0]])
    errors = np.array([[0.02, 0.0], [0.03, 0.0], [0.2, 0.0], [0.3, 0.0]])
    assert field_coverage(field, xy, errors) == pytest.approx(0.5)
    assert field_coverage(field, xy, errors, floor_std=0.1) == pytest.approx(0.75)
    assert np.isnan(field_coverage(field, np.zeros((0, 2)), np.zeros((0, 2))))
