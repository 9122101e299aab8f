"""The robot's camera model: intrinsics, distortion and its inverse."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.camera_model import (
    CameraModel,
    check_dist_coeffs,
    focal_from_hfov,
    undistort_points,
)
from symloc.errors import ConfigurationError

RPI_V2 = (0.1349735, -0.2335870, 0.0006697, 0.0048467, 0.0)


def test_from_hfov_and_matrix() -> None:
    cam = CameraModel.from_hfov(640, 480, math.radians(90.0))
    assert np.allclose(cam.K, [[320, 0, 320], [0, 320, 240], [0, 0, 1]])
    assert not cam.has_distortion
    assert cam.dist_coeffs == (0.0,) * 5
    assert focal_from_hfov(640, math.radians(90.0)) == pytest.approx(320.0)


@settings(max_examples=30, deadline=None)
@given(
    k1=st.floats(-0.3, 0.3),
    k2=st.floats(-0.3, 0.3),
    p1=st.floats(-0.005, 0.005),
    p2=st.floats(-0.005, 0.005),
)
def test_distortion_round_trip(k1: float, k2: float, p1: float, p2: float) -> None:
    cam = CameraModel.from_hfov(dist_coeffs=(k1, k2, p1, p2, 0.0))
    rng = np.random.default_rng(0)
    ideal = rng.uniform([40, 30], [600, 450], (200, 2))
    distorted = cam.distort_points(ideal)
    back = cam.undistort_points(distorted)
    assert np.abs(back - ideal).max() < 0.05


def test_distortion_matches_the_opencv_formula() -> None:
    cam = CameraModel.from_hfov(dist_coeffs=RPI_V2)
    k1, k2, p1, p2, k3 = RPI_V2
    u, v = 500.0, 100.0
    x = (u - cam.cx) / cam.fx
    y = (v - cam.cy) / cam.fy
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    out = cam.distort_points([[u, v]])[0]
    assert out == pytest.approx([cam.cx + cam.fx * xd, cam.cy + cam.fy * yd], abs=1e-6)
    assert np.array_equal(undistort_points([[u, v]], cam.K, None), [[u, v]])


def test_bad_calibration_raises() -> None:
    with pytest.raises(ConfigurationError, match="dist_coeffs: expected 4 or 5 numbers"):
        check_dist_coeffs([0.1, 0.2, 0.3])
    with pytest.raises(ConfigurationError, match="NaN"):
        check_dist_coeffs([0.1, math.nan, 0, 0])
    assert check_dist_coeffs([]) == (0.0,) * 5
    assert check_dist_coeffs([0.1, 0.2, 0.0, 0.0]) == (0.1, 0.2, 0.0, 0.0, 0.0)
    with pytest.raises(ConfigurationError, match=r"CameraModel\.fx"):
        CameraModel(640, 480, 0.0, 500.0, 320.0, 240.0)
    with pytest.raises(ConfigurationError, match=r"CameraModel\.width"):
        CameraModel(0, 480, 500.0, 500.0, 320.0, 240.0)
    with pytest.raises(ConfigurationError, match=r"CameraModel\.dist_coeffs"):
        CameraModel(640, 480, 500.0, 500.0, 320.0, 240.0, (1.0,))
