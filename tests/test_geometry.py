from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from symloc.errors import ConfigurationError
from symloc.geometry import (
    angle_diff,
    as_pose,
    circular_mean,
    compose,
    from_matrix,
    inverse,
    relative,
    to_matrix,
    transform_points,
    wrap_angle,
)

coord = st.floats(-1e3, 1e3, allow_nan=False)
angle = st.floats(-20.0, 20.0, allow_nan=False)
pose_st = st.tuples(coord, coord, angle).map(lambda t: np.array(t))
poses_st = arrays(np.float64, (7, 3), elements=st.floats(-100, 100, allow_nan=False))


def assert_pose_close(a: np.ndarray, b: np.ndarray, atol: float = 1e-6) -> None:
    np.testing.assert_allclose(a[..., :2], b[..., :2], atol=atol)
    np.testing.assert_allclose(angle_diff(a[..., 2], b[..., 2]), 0.0, atol=atol)


def test_wrap_angle_interval_is_half_open() -> None:
    assert wrap_angle(np.pi) == pytest.approx(np.pi)
    assert wrap_angle(-np.pi) == pytest.approx(np.pi)
    assert wrap_angle(3 * np.pi / 2) == pytest.approx(-np.pi / 2)
    assert isinstance(wrap_angle(1.0), float)
    out = wrap_angle(np.linspace(-50, 50, 1001))
    assert np.all(out > -np.pi)
    assert np.all(out <= np.pi)


@given(angle)
def test_wrap_angle_preserves_direction(a: float) -> None:
    w = wrap_angle(a)
    assert np.cos(w) == pytest.approx(np.cos(a), abs=1e-9)
    assert np.sin(w) == pytest.approx(np.sin(a), abs=1e-9)


@given(pose_st)
def test_compose_with_inverse_is_identity(p: np.ndarray) -> None:
    assert_pose_close(compose(p, inverse(p)), np.zeros(3), atol=1e-6)
    assert_pose_close(compose(inverse(p), p), np.zeros(3), atol=1e-6)


@given(pose_st, pose_st, pose_st)
def test_compose_is_associative(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> None:
    assert_pose_close(compose(compose(a, b), c), compose(a, compose(b, c)), atol=1e-5)


@given(poses_st)
def test_compose_vectorised_matches_matrices(p: np.ndarray) -> None:
    q = p[::-1]
    via_matrix = from_matrix(to_matrix(p) @ to_matrix(q))
    assert_pose_close(compose(p, q), via_matrix, atol=1e-6)


@given(pose_st, pose_st)
def test_relative_recovers_second_pose(a: np.ndarray, b: np.ndarray) -> None:
    assert_pose_close(compose(a, relative(a, b)), b, atol=1e-5)


def test_transform_points_hand_computed() -> None:
    pose = np.array([1.0, 2.0, np.pi / 2])
    pts = np.array([[1.0, 0.0], [0.0, 1.0]])
    np.testing.assert_allclose(transform_points(pose, pts), [[1.0, 3.0], [0.0, 2.0]], atol=1e-12)
    many = transform_points(np.stack([pose, np.zeros(3)]), pts)
    assert many.shape == (2, 2, 2)
    np.testing.assert_allclose(many[1], pts)


def test_transform_points_rejects_bad_shape() -> None:
    with pytest.raises(ConfigurationError, match=r"points_b: expected shape \(N, 2\)"):
        transform_points(np.zeros(3), np.zeros((4, 3)))


def test_circular_mean_across_seam() -> None:
    assert abs(angle_diff(circular_mean([np.pi - 0.1, -np.pi + 0.1]), np.pi)) < 1e-12


def test_as_pose_errors() -> None:
    with pytest.raises(ConfigurationError, match=r"pose: expected shape \(\.\.\., 3\)"):
        as_pose([1.0, 2.0])
    with pytest.raises(ConfigurationError, match="NaN"):
        as_pose([1.0, np.nan, 0.0])
