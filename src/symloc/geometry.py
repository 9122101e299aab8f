"""SE(2) poses and transforms, vectorised over many poses.

A pose is an array ``(..., 3)`` holding ``x [m], y [m], theta [rad]``; it maps points from its
own frame into the parent frame. Names follow ``a_from_b``: ``compose(a_from_b, b_from_c)``
returns ``a_from_c``. All functions broadcast over leading dimensions, so the same code serves
one pose ``(3,)`` and a particle set ``(N, 3)``. Angles are wrapped to (-pi, pi].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError

__all__ = [
    "angle_diff",
    "as_pose",
    "circular_mean",
    "compose",
    "from_matrix",
    "inverse",
    "relative",
    "rotation_matrix",
    "to_matrix",
    "transform_points",
    "wrap_angle",
]

FloatArray = NDArray[np.float64]

_TWO_PI = 2.0 * math.pi


def wrap_angle(angle: ArrayLike) -> Any:
    """Wrap angles [rad] to the half-open interval (-pi, pi].

    ``pi`` stays ``pi`` and ``-pi`` becomes ``pi``, so every direction has exactly one value.
    Returns a float for scalar input, an array of the input's shape otherwise.
    """
    if isinstance(angle, (float, int)):
        # one number: Python's float remainder is NumPy's (fmod, then the divisor's sign),
        # bit for bit, without an array round trip (the filter wraps a few per scan)
        return math.pi - (math.pi - float(angle)) % _TWO_PI
    a = np.asarray(angle, dtype=np.float64)
    out = np.pi - np.mod(np.pi - a, 2.0 * np.pi)
    return float(out) if out.ndim == 0 else out


def angle_diff(a: ArrayLike, b: ArrayLike) -> Any:
    """Signed smallest difference ``a - b`` [rad], wrapped to (-pi, pi]."""
    return wrap_angle(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64))


def circular_mean(angles: ArrayLike, weights: ArrayLike | None = None) -> float:
    """Weighted circular mean of ``angles`` (N,) [rad], wrapped to (-pi, pi]."""
    a = np.asarray(angles, dtype=np.float64)
    w = np.ones_like(a) if weights is None else np.asarray(weights, dtype=np.float64)
    return float(wrap_angle(np.arctan2(np.sum(w * np.sin(a)), np.sum(w * np.cos(a)))))


def as_pose(pose: ArrayLike, name: str = "pose") -> FloatArray:
    """Validate and return poses as a float array of shape ``(..., 3)`` with finite values."""
    try:
        p = np.asarray(pose, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ConfigurationError(f"{name}: cannot convert to a float array") from err
    if p.ndim == 0 or p.shape[-1] != 3:
        raise ConfigurationError(f"{name}: expected shape (..., 3) as x, y, theta; got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ConfigurationError(f"{name}: contains NaN or infinite values")
    return p


def rotation_matrix(theta: ArrayLike) -> FloatArray:
    """Rotation matrices ``(..., 2, 2)`` for angles ``(...)`` [rad]."""
    t = np.asarray(theta, dtype=np.float64)
    c, s = np.cos(t), np.sin(t)
    return np.stack([np.stack([c, -s], axis=-1), np.stack([s, c], axis=-1)], axis=-2)


def compose(a_from_b: ArrayLike, b_from_c: ArrayLike) -> FloatArray:
    """Compose poses: ``a_from_c = a_from_b * b_from_c``.

    Parameters
    ----------
    a_from_b, b_from_c : array of shape (..., 3)
        Broadcast against each other.

    Returns
    -------
    ndarray of shape (..., 3)
    """
    ab = np.asarray(a_from_b, dtype=np.float64)
    bc = np.asarray(b_from_c, dtype=np.float64)
    c, s = np.cos(ab[..., 2]), np.sin(ab[..., 2])
    x = ab[..., 0] + c * bc[..., 0] - s * bc[..., 1]
    y = ab[..., 1] + s * bc[..., 0] + c * bc[..., 1]
    return np.stack([x, y, wrap_angle(ab[..., 2] + bc[..., 2])], axis=-1)


def inverse(a_from_b: ArrayLike) -> FloatArray:
    """Invert poses: ``b_from_a``. Shape ``(..., 3)`` in and out."""
    p = np.asarray(a_from_b, dtype=np.float64)
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    x = -(c * p[..., 0] + s * p[..., 1])
    y = s * p[..., 0] - c * p[..., 1]
    return np.stack([x, y, wrap_angle(-p[..., 2])], axis=-1)


def relative(world_from_a: ArrayLike, world_from_b: ArrayLike) -> FloatArray:
    """The pose of b in a's frame, ``a_from_b = inverse(world_from_a) * world_from_b``."""
    return compose(inverse(world_from_a), world_from_b)


def turn_about(poses: ArrayLike, centre: ArrayLike, turn: ArrayLike) -> FloatArray:
    """``poses`` (..., 3) turned by ``turn`` [rad] (broadcast) about the point ``centre`` (2,)
    [m]: position and heading together, as a rigid rotation of the plane."""
    c = np.asarray(centre, dtype=np.float64).reshape(2)
    t = np.asarray(turn, dtype=np.float64)
    cos, sin = np.cos(t), np.sin(t)
    about = np.stack(
        np.broadcast_arrays(c[0] - (cos * c[0] - sin * c[1]), c[1] - (sin * c[0] + cos * c[1]), t),
        axis=-1,
    )
    return compose(about, poses)


def transform_points(a_from_b: ArrayLike, points_b: ArrayLike) -> FloatArray:
    """Map points from frame b into frame a.

    Parameters
    ----------
    a_from_b : array of shape (3,) or (M, 3)
    points_b : array of shape (N, 2)

    Returns
    -------
    ndarray of shape (N, 2) for one pose, (M, N, 2) for M poses.
    """
    p = np.asarray(a_from_b, dtype=np.float64)
    pts = np.asarray(points_b, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ConfigurationError(f"points_b: expected shape (N, 2), got {pts.shape}")
    if p.ndim == 1:
        c, s = np.cos(p[2]), np.sin(p[2])
        return np.column_stack(
            [p[0] + c * pts[:, 0] - s * pts[:, 1], p[1] + s * pts[:, 0] + c * pts[:, 1]]
        )
    c = np.cos(p[:, 2])[:, None]
    s = np.sin(p[:, 2])[:, None]
    x = p[:, 0, None] + c * pts[None, :, 0] - s * pts[None, :, 1]
    y = p[:, 1, None] + s * pts[None, :, 0] + c * pts[None, :, 1]
    return np.stack([x, y], axis=-1)


def to_matrix(pose: ArrayLike) -> FloatArray:
    """Homogeneous matrices ``(..., 3, 3)`` from poses ``(..., 3)``."""
    p = np.asarray(pose, dtype=np.float64)
    m = np.zeros((*p.shape[:-1], 3, 3))
    m[..., :2, :2] = rotation_matrix(p[..., 2])
    m[..., 0, 2] = p[..., 0]
    m[..., 1, 2] = p[..., 1]
    m[..., 2, 2] = 1.0
    return m


def from_matrix(matrix: ArrayLike) -> FloatArray:
    """Poses ``(..., 3)`` from homogeneous matrices ``(..., 3, 3)``."""
    m = np.asarray(matrix, dtype=np.float64)
    if m.shape[-2:] != (3, 3):
        raise ConfigurationError(f"matrix: expected shape (..., 3, 3), got {m.shape}")
    theta = np.arctan2(m[..., 1, 0], m[..., 0, 0])
    return np.stack([m[..., 0, 2], m[..., 1, 2], wrap_angle(theta)], axis=-1)
