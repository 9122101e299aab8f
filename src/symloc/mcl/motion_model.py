"""Odometry motion models: ``sample_motion_model_odometry`` (Thrun et al. 2005, Table 5.6).

Four variants, as ROS 1 amcl's ``odom_model_type``:

``diff-corrected``
    Differential drive, nav2_amcl's ``DifferentialMotionModel``. Noise standard deviations
    ``sqrt(alpha1 rot^2 + alpha2 trans^2)`` etc. Backward and forward motion are treated alike
    (the rotation noise uses the smaller of ``|rot|`` and ``|pi - rot|``).
``diff``
    ROS 1 amcl's original differential model, which used the *variance* expression as the
    standard deviation (``alpha1 rot^2 + alpha2 trans^2``); kept for users whose alphas were
    tuned against it.
``omni-corrected``
    Omnidirectional drive, nav2_amcl's ``OmniMotionModel``: translation, strafe and rotation
    noises with ``alpha1..alpha5``, standard deviations as square roots of the variances.
``omni``
    ROS 1 amcl's original omni model (variance used as standard deviation).

All functions are vectorised over particles and return new arrays; the differential models'
per-particle update runs in a compiled loop (:mod:`symloc.mcl.kernels`) with the same
expressions, bit for bit.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError, DataFormatError
from symloc.geometry import angle_diff, compose, relative, wrap_angle
from symloc.mcl import kernels

__all__ = [
    "MOTION_VARIANTS",
    "Odometer",
    "carry_by_odometry",
    "folded_rotations",
    "increment",
    "odometry_delta",
    "sample_motion_model_odometry",
]

FloatArray = NDArray[np.float64]

MOTION_VARIANTS = ("diff", "diff-corrected", "omni", "omni-corrected")


def odometry_delta(odom_prev: FloatArray, odom_curr: FloatArray) -> FloatArray:
    """The odometry change ``(3,)`` as nav2 computes it: dx, dy in the odom frame, dtheta."""
    a = np.asarray(odom_prev, dtype=np.float64)
    b = np.asarray(odom_curr, dtype=np.float64)
    if a.shape != (3,) or b.shape != (3,):
        raise DataFormatError("odometry poses: expected shape (3,) as x, y, theta")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise DataFormatError(f"odometry poses: expected finite values, got {a} and {b}")
    return np.array([b[0] - a[0], b[1] - a[1], angle_diff(b[2], a[2])])


def sample_motion_model_odometry(
    particles: FloatArray,
    odom_prev: FloatArray,
    odom_curr: FloatArray,
    alphas: tuple[float, float, float, float, float],
    rng: np.random.Generator,
    *,
    model: str = "diff-corrected",
    out: FloatArray | None = None,
) -> FloatArray:
    """Move every particle by the odometry increment with sampled noise.

    Parameters
    ----------
    particles : ndarray of shape (N, 3)
        Particle poses x [m], y [m], theta [rad] in the map frame.
    odom_prev, odom_curr : ndarray of shape (3,)
        Odometry poses (odom frame) at the previous filter update and now.
    alphas : tuple of 5 floats
        nav2's alpha1..alpha5 (alpha5 only for the omni models), each >= 0.
    rng : numpy.random.Generator
        Source of the noise.
    model : str
        One of ``diff``, ``diff-corrected``, ``omni``, ``omni-corrected``.
    out : ndarray of shape (N, 3), optional
        Where to write the result (may be ``particles`` itself).

    Returns
    -------
    ndarray of shape (N, 3)
        The moved particles, theta wrapped to (-pi, pi].
    """
    if model not in MOTION_VARIANTS:
        raise ConfigurationError(f"model: expected one of {MOTION_VARIANTS}, got {model!r}")
    if len(alphas) != 5 or any((not np.isfinite(a)) or a < 0 for a in alphas):
        raise ConfigurationError(f"alphas: expected five finite values >= 0, got {alphas}")
    p = np.asarray(particles, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ConfigurationError(f"particles: expected shape (N, 3), got {p.shape}")
    a1, a2, a3, a4, a5 = (float(a) for a in alphas)
    prev = np.asarray(odom_prev, dtype=np.float64)
    delta = odometry_delta(prev, odom_curr)
    n = p.shape[0]
    res = np.empty_like(p) if out is None else out
    trans = float(np.hypot(delta[0], delta[1]))
    corrected = model.endswith("corrected")
    if model.startswith("diff"):
        rot1, _, rot2 = _split(prev, delta)
        # Treat backward and forward motion symmetrically for the noise.
        r1n, r2n = folded_rotations(rot1, rot2)
        v_r1 = a1 * r1n * r1n + a2 * trans * trans
        v_tr = a3 * trans * trans + a4 * r1n * r1n + a4 * r2n * r2n
        v_r2 = a1 * r2n * r2n + a2 * trans * trans
        s_r1, s_tr, s_r2 = np.sqrt([v_r1, v_tr, v_r2]) if corrected else (v_r1, v_tr, v_r2)
        noise = rng.standard_normal((3, n))
        if p.flags.c_contiguous and res.flags.c_contiguous and np.isfinite(p).all():
            # compiled: the same expressions per particle, no (N,) temporaries
            kernels.move_diff(p, noise, rot1, trans, rot2, s_r1, s_tr, s_r2, res)
            return res
        r1_hat = rot1 - s_r1 * noise[0]
        tr_hat = trans - s_tr * noise[1]
        r2_hat = rot2 - s_r2 * noise[2]
        heading = p[:, 2] + r1_hat
        x = p[:, 0] + tr_hat * np.cos(heading)
        y = p[:, 1] + tr_hat * np.sin(heading)
        th = heading + r2_hat
    else:
        rot = float(delta[2])
        v_tr = a3 * trans * trans + a1 * rot * rot
        v_rot = a4 * rot * rot + a2 * trans * trans
        v_st = a1 * rot * rot + a5 * trans * trans
        s_tr, s_rot, s_st = np.sqrt([v_tr, v_rot, v_st]) if corrected else (v_tr, v_rot, v_st)
        noise = rng.standard_normal((3, n))
        bearing = float(angle_diff(np.arctan2(delta[1], delta[0]), prev[2])) + p[:, 2]
        cb = np.cos(bearing)
        sb = np.sin(bearing)
        tr_hat = trans + s_tr * noise[0]
        rot_hat = rot + s_rot * noise[1]
        st_hat = s_st * noise[2]
        x = p[:, 0] + tr_hat * cb + st_hat * sb
        y = p[:, 1] + tr_hat * sb - st_hat * cb
        th = p[:, 2] + rot_hat
    res[:, 0] = x
    res[:, 1] = y
    res[:, 2] = wrap_angle(th)
    return res


def increment(odom_prev: FloatArray, odom_curr: FloatArray) -> tuple[float, float, float]:
    """The odometry increment ``odom_prev -> odom_curr`` (3,) as ``rot1, trans, rot2``
    [rad, m, rad] (Thrun et al. 2005, Table 5.6), no first rotation below 1 cm of travel (as
    nav2: the direction of a tiny step is noise)."""
    prev = np.asarray(odom_prev, dtype=np.float64)
    return _split(prev, odometry_delta(prev, odom_curr))


def _split(prev: FloatArray, delta: FloatArray) -> tuple[float, float, float]:
    """:func:`increment` from the previous pose (3,) and its :func:`odometry_delta` (3,)."""
    trans = float(np.hypot(delta[0], delta[1]))
    rot1 = 0.0 if trans < 0.01 else float(angle_diff(np.arctan2(delta[1], delta[0]), prev[2]))
    return rot1, trans, float(angle_diff(delta[2], rot1))


def folded_rotations(rot1: float, rot2: float) -> tuple[float, float]:
    """``|rot1|``, ``|rot2|`` [rad] folded as nav2 folds them (``min(|r|, pi - |r|)``: a step
    backwards is as noisy as one forwards)."""
    return (
        min(abs(float(angle_diff(rot1, 0.0))), abs(float(angle_diff(rot1, np.pi)))),
        min(abs(float(angle_diff(rot2, 0.0))), abs(float(angle_diff(rot2, np.pi)))),
    )


class Odometer:
    """The path [m] and turning [rad] the odometry went through, summed step by step.

    Fed every odometry pose in order (:meth:`advance`; the same pose twice adds nothing), it
    tells how much motion lies between two readings (:meth:`since`), which
    :func:`carry_by_odometry` needs to grow a covariance carried over many steps: each step
    adds its translation and its folded ``|rot1| + |rot2|`` (the motion model's own measure of
    turning).
    """

    def __init__(self) -> None:
        self._last: FloatArray | None = None
        self.path = 0.0
        self.turning = 0.0

    def advance(self, odom_pose: FloatArray) -> tuple[float, float]:
        """Add the step to ``odom_pose`` (3,); returns the totals ``(path, turning)``."""
        odom = np.asarray(odom_pose, dtype=np.float64).reshape(3)
        if self._last is not None:
            rot1, trans, rot2 = increment(self._last, odom)
            r1n, r2n = folded_rotations(rot1, rot2)
            self.path += trans
            self.turning += r1n + r2n
        self._last = odom.copy()
        return self.path, self.turning

    @property
    def reading(self) -> tuple[float, float]:
        """The totals ``(path, turning)`` so far."""
        return self.path, self.turning

    def since(self, reading: tuple[float, float]) -> tuple[float, float]:
        """The motion ``(path, turning)`` since an earlier :attr:`reading`."""
        return max(0.0, self.path - reading[0]), max(0.0, self.turning - reading[1])


def carry_by_odometry(
    pose: FloatArray,
    covariance: FloatArray,
    odom_prev: FloatArray,
    odom_curr: FloatArray,
    alphas: tuple[float, float, float, float],
    *,
    travelled: tuple[float, float] | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Move a pose estimate by the odometry increment; grow its covariance by the motion model.

    The increment ``odom_prev -> odom_curr`` is split into ``rot1, trans, rot2`` (Thrun et
    al. 2005, Table 5.6) and applied to ``pose`` (3,); the covariance (3, 3) is propagated to
    first order, ``F C F^T + G Q G^T``, with ``Q = diag(a1 rot1^2 + a2 trans^2,
    a3 trans^2 + a4 (rot1^2 + rot2^2), a1 rot2^2 + a2 trans^2)`` (the variances of the
    ``diff-corrected`` model, backward motion folded as nav2 folds it). The mean is the exact
    composition ``pose * (odom_prev^-1 * odom_curr)``. Returns
    ``(pose (3,), covariance (3, 3))``: what a ``map -> odom`` transform gives between filter
    updates, with its uncertainty.

    ``travelled`` ``(path [m], turning [rad])``: what the odometry went through between the
    two poses (:class:`Odometer`), when the increment spans more than one step. The noise then
    grows with the path and the turning, not with the net increment: a robot that turned back
    and forth, or drove out and back, has the error of all that motion although its net
    increment is small. The translation noise uses ``max(trans, path)``, the rotation noises
    are scaled up so that ``|rot1| + |rot2|`` reaches ``turning``, and a heading error along the
    way moves the position by up to ``path`` times it. Never less than without it.
    """
    a1, a2, a3, a4 = (float(a) for a in alphas)
    prev = np.asarray(odom_prev, dtype=np.float64)
    rot1, trans, rot2 = increment(prev, odom_curr)
    r1n, r2n = folded_rotations(rot1, rot2)
    moved = trans
    if travelled is not None:
        path, turning = (float(v) for v in travelled)
        moved = max(trans, path)
        turned = r1n + r2n
        if turning > turned:
            if turned > 0.0:
                r1n, r2n = r1n * turning / turned, r2n * turning / turned
            else:
                r2n = turning
    q = np.diag(
        [
            a1 * r1n * r1n + a2 * moved * moved,
            a3 * moved * moved + a4 * (r1n * r1n + r2n * r2n),
            a1 * r2n * r2n + a2 * moved * moved,
        ]
    )
    p = np.asarray(pose, dtype=np.float64)
    heading = float(p[2]) + rot1
    c, s = np.cos(heading), np.sin(heading)
    out = compose(p, relative(prev, np.asarray(odom_curr, dtype=np.float64)))
    f = np.array([[1.0, 0.0, -trans * s], [0.0, 1.0, trans * c], [0.0, 0.0, 1.0]])
    g = np.array([[-moved * s, c, 0.0], [moved * c, s, 0.0], [1.0, 0.0, 1.0]])
    cov = f @ np.asarray(covariance, dtype=np.float64) @ f.T + g @ q @ g.T
    return out, 0.5 * (cov + cov.T)
