"""What the odometry is worth, learnt from the run itself: calibration and noise.

The SLAM front end reports every graph node: its raw odometry pose and, when its scan match
constrained every direction, the pose the match alone gave. Over a sliding window of the most
recent nodes, for every pair of matched nodes up to ``max_lag`` nodes apart, the increment
the odometry reported is compared with the increment the matches found:

- **calibration**: the scale of the odometry's translations and rotations
  (``trans_odo ~ trans_match / s_t``, ``rot_odo ~ rot_match / s_r``, least squares through
  the origin with the matches as the regressor: they are far less noisy, and regressing on
  the odometry would shrink the scales by its noise), the systematic errors of a wrong wheel diameter and wheel base (Borenstein &
  Feng 1996); applied to every increment;
- **noise**: the variances of the remaining differences, modelled as Thrun's odometry model
  summed over the steps between the two nodes plus a constant, the matcher's own error
  (entering twice in a difference of two matches): ``var = c + a * sum(trans^2) +
  b * sum(rot^2)``. Pairs several steps apart separate the constant from the motion terms
  (a difference of two matches does not grow with the distance between them; odometry error
  does). Fitted by iteratively reweighted non-negative least squares on the squared
  differences (weights ``1 / var^2``; differences beyond 3 standard deviations dropped as
  outliers), translation and heading separately.

Before ``min_pairs`` pairs are in, a deliberately generous prior (GMapping's default noise
model: 20 % of a rotation, 0.1 rad and 0.2 m per metre) is used, so that the front end
searches widely until it has learnt otherwise. Nothing here is tuned per log: every number
comes from the run's own data or from the prior.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import nnls

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import relative, wrap_angle
from symloc.odometry import rot_trans_rot, rot_trans_rot_to_pose

__all__ = ["OdometryModel", "OdometryModelParams"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class OdometryModelParams:
    """Settings of :class:`OdometryModel`.

    Parameters
    ----------
    window : int
        Most recent nodes used for the fits.
    min_pairs : int
        Matched nodes needed before the fitted model replaces the prior.
    max_lag : int
        Pairs of matched nodes up to this many nodes apart enter the fits.
    refit_every : int
        Pairs between refits.
    prior : tuple of 4 floats
        ``(a_rot_rot [rad^2/rad^2], a_rot_trans [rad^2/m^2], a_trans_trans [m^2/m^2],
        a_trans_rot [m^2/rad^2])`` of the prior (Thrun's alpha1..alpha4).
    floor_trans, floor_rot : float
        Smallest standard deviation of an increment [m], [rad].
    max_calibration_error : float
        Scale factors are only applied within ``1 +- this``.
    """

    window: int = 300
    min_pairs: int = 30
    max_lag: int = 4
    refit_every: int = 10
    prior: tuple[float, float, float, float] = (0.04, 0.01, 0.04, 0.04)
    floor_trans: float = 0.005
    floor_rot: float = math.radians(0.2)
    max_calibration_error: float = 0.1

    def __post_init__(self) -> None:
        for name in ("window", "min_pairs", "refit_every", "max_lag"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ConfigurationError(
                    f"OdometryModelParams.{name}: expected an integer >= 1, got {v}"
                )
        if len(self.prior) != 4:
            raise ConfigurationError("OdometryModelParams.prior: expected 4 values")
        for k, a in enumerate(self.prior):
            check_positive(a, f"OdometryModelParams.prior[{k}]", allow_zero=True)
        check_positive(self.floor_trans, "OdometryModelParams.floor_trans")
        check_positive(self.floor_rot, "OdometryModelParams.floor_rot")
        check_positive(self.max_calibration_error, "OdometryModelParams.max_calibration_error")


def _motions(increments: FloatArray) -> FloatArray:
    """``(K, 2)`` translation [m] and total absolute rotation [rad] of increments (K, 3)."""
    inc = np.asarray(increments, dtype=np.float64).reshape(-1, 3)
    r1, tr, r2 = rot_trans_rot(np.zeros((inc.shape[0], 3)), inc)
    q1 = np.minimum(np.abs(r1), math.pi - np.abs(r1))
    q2 = np.minimum(np.abs(r2), math.pi - np.abs(r2))
    # a turn on the spot: the direction of travel is meaningless, the turn is the heading
    rot = np.where(tr < 0.05, np.abs(wrap_angle(inc[:, 2])), q1 + q2)
    return np.column_stack([tr, rot])


class OdometryModel:
    """Online calibration and noise model of the odometry (see the module docstring)."""

    def __init__(self, params: OdometryModelParams | None = None) -> None:
        self.params = params if params is not None else OdometryModelParams()
        w = self.params.window
        self._odo: deque[FloatArray] = deque(maxlen=w)
        self._match: deque[FloatArray | None] = deque(maxlen=w)
        self._since_fit = 0
        self.trans_scale = 1.0
        self.rot_scale = 1.0
        a1, a2, a3, a4 = self.params.prior
        # var_trans (per axis) = c_t + a_tt trans^2 + a_tr rot^2; var_rot likewise
        self.coef_trans = np.array([0.0, a3, a4])
        self.coef_rot = np.array([0.0, a2, a1])
        self.fitted = False
        self.n_pairs = 0

    def add_node(self, odometry_pose: ArrayLike, match_pose: ArrayLike | None) -> None:
        """Record a node: its raw odometry pose (3,) and its match-only pose (3,) or None."""
        self._odo.append(np.asarray(odometry_pose, dtype=np.float64).reshape(3).copy())
        self._match.append(
            None if match_pose is None else np.asarray(match_pose, dtype=np.float64).reshape(3)
        )
        if match_pose is not None:
            self.n_pairs += 1
        self._since_fit += 1
        if self.n_pairs >= self.params.min_pairs and self._since_fit >= self.params.refit_every:
            self._fit()
            self._since_fit = 0

    def _pairs(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Raw odometry and match increments (P, 3) of matched pairs, and (P, 2) motion sums."""
        odo = np.array(self._odo)
        has = np.array([m is not None for m in self._match])
        mat = np.array([m if m is not None else np.zeros(3) for m in self._match])
        steps = np.vstack([np.zeros((1, 3)), relative(odo[:-1], odo[1:])])
        cum = np.cumsum(_motions(self.correct_many(steps)) ** 2, axis=0)
        js, ks = [], []
        for lag in range(1, self.params.max_lag + 1):
            k = np.arange(lag, odo.shape[0])
            ok = has[k] & has[k - lag]
            js.append(k[ok] - lag)
            ks.append(k[ok])
        j = np.concatenate(js)
        k = np.concatenate(ks)
        return relative(odo[j], odo[k]), relative(mat[j], mat[k]), cum[k] - cum[j]

    def _fit(self) -> None:
        odo, mat, feat = self._pairs()
        if odo.shape[0] < self.params.min_pairs:
            return
        lim = self.params.max_calibration_error
        t_o = np.hypot(odo[:, 0], odo[:, 1])
        t_m = np.hypot(mat[:, 0], mat[:, 1])
        r_o = wrap_angle(odo[:, 2])
        r_m = wrap_angle(mat[:, 2])
        mv = t_o > 0.1
        # odometry regressed on the (far less noisy) matches, then inverted: regressing the
        # other way round would shrink the scale by the odometry's own noise
        if mv.sum() >= self.params.min_pairs // 2:
            s = float(np.sum(t_m[mv] ** 2) / np.sum(t_m[mv] * t_o[mv]))
            self.trans_scale = min(max(s, 1 - lim), 1 + lim)
        tn = (np.abs(r_m) > math.radians(10)) & (np.abs(r_m) < math.radians(150))
        if tn.sum() >= self.params.min_pairs // 2:
            s = float(np.sum(r_m[tn] ** 2) / np.sum(r_m[tn] * r_o[tn]))
            self.rot_scale = min(max(s, 1 - lim), 1 + lim)
        corrected = self.correct_many(odo)
        e = relative(corrected, mat)
        y_t = 0.5 * (e[:, 0] ** 2 + e[:, 1] ** 2)
        y_r = wrap_angle(e[:, 2]) ** 2
        design = np.column_stack([np.ones(len(e)), feat])
        self.coef_trans = _irls(design, y_t, self.coef_trans)
        self.coef_rot = _irls(design, y_r, self.coef_rot)
        self.fitted = True

    def correct(self, increment: ArrayLike) -> FloatArray:
        """The increment (3,) with the learnt calibration applied."""
        inc = np.asarray(increment, dtype=np.float64).reshape(3)
        if self.trans_scale == 1.0 and self.rot_scale == 1.0:
            return inc.copy()
        r1, tr, r2 = rot_trans_rot(np.zeros(3), inc)
        if float(tr) < 0.05:  # on the spot: scale the turn only
            return np.array([inc[0], inc[1], float(wrap_angle(inc[2] * self.rot_scale))])
        return np.asarray(
            rot_trans_rot_to_pose(
                np.zeros(3),
                float(r1) * self.rot_scale,
                float(tr) * self.trans_scale,
                float(r2) * self.rot_scale,
            ),
            dtype=np.float64,
        )

    def correct_many(self, increments: ArrayLike) -> FloatArray:
        """Increments (K, 3) with the learnt calibration applied."""
        inc = np.asarray(increments, dtype=np.float64).reshape(-1, 3)
        if self.trans_scale == 1.0 and self.rot_scale == 1.0:
            return inc.copy()
        zero = np.zeros((inc.shape[0], 3))
        r1, tr, r2 = rot_trans_rot(zero, inc)
        out = np.asarray(
            rot_trans_rot_to_pose(
                zero, r1 * self.rot_scale, tr * self.trans_scale, r2 * self.rot_scale
            ),
            dtype=np.float64,
        ).reshape(-1, 3)
        spot = tr < 0.05  # on the spot: scale the turn only
        out[spot, :2] = inc[spot, :2]
        out[spot, 2] = wrap_angle(inc[spot, 2] * self.rot_scale)
        return out

    def sigmas(self, increment: ArrayLike) -> tuple[float, float]:
        """``(sigma_trans [m] per axis, sigma_rot [rad])`` of a (corrected) increment (3,)."""
        tr, rot = _motions(np.asarray(increment, dtype=np.float64).reshape(1, 3))[0]
        x = np.array([0.0, tr * tr, rot * rot])
        st = math.sqrt(max(float(self.coef_trans @ x), 0.0))
        sr = math.sqrt(max(float(self.coef_rot @ x), 0.0))
        return max(st, self.params.floor_trans), max(sr, self.params.floor_rot)

    def covariance(self, increment: ArrayLike) -> FloatArray:
        """``(3, 3)`` diagonal covariance of a (corrected) odometry increment (3,)."""
        st, sr = self.sigmas(increment)
        return np.diag([st * st, st * st, sr * sr])

    def generous_covariance(self, increment: ArrayLike) -> FloatArray:
        """The larger of :meth:`covariance` and the prior's: for decisions that must not
        refuse a correct match because the fit is optimistic (the odometry gate)."""
        tr, rot = _motions(np.asarray(increment, dtype=np.float64).reshape(1, 3))[0]
        a1, a2, a3, a4 = self.params.prior
        vt = a3 * tr * tr + a4 * rot * rot
        vr = a2 * tr * tr + a1 * rot * rot
        c = self.covariance(increment)
        return np.diag([max(c[0, 0], vt), max(c[1, 1], vt), max(c[2, 2], vr)])

    @property
    def matcher_sigmas(self) -> tuple[float, float]:
        """``(sigma_trans [m], sigma_rot [rad])`` of one scan match: half the fitted constant."""
        st = math.sqrt(max(float(self.coef_trans[0]) / 2.0, 0.0))
        sr = math.sqrt(max(float(self.coef_rot[0]) / 2.0, 0.0))
        return st, sr

    def summary(self) -> dict[str, float | bool | int]:
        """The learnt figures (for the run's summary)."""
        mt, mr = self.matcher_sigmas
        return {
            "matched_nodes": self.n_pairs,
            "fitted": self.fitted,
            "trans_scale": self.trans_scale,
            "rot_scale": self.rot_scale,
            "trans_per_m": math.sqrt(float(self.coef_trans[1])),
            "trans_per_rad": math.sqrt(float(self.coef_trans[2])),
            "rot_per_rad": math.sqrt(float(self.coef_rot[2])),
            "rot_per_m": math.sqrt(float(self.coef_rot[1])),
            "matcher_trans_m": mt,
            "matcher_rot_rad": mr,
        }


def _irls(design: FloatArray, y: FloatArray, start: FloatArray, iterations: int = 4) -> FloatArray:
    """Non-negative fit of ``y ~ design @ coef`` with weights ``1 / var^2``, outliers dropped."""
    coef = np.asarray(start, dtype=np.float64).copy()
    keep = np.ones(y.size, dtype=bool)
    for _ in range(iterations):
        var = np.maximum(design @ coef, 1e-10)
        keep = y <= 9.0 * var  # within 3 standard deviations
        if keep.sum() < design.shape[1] * 3:
            keep = np.ones(y.size, dtype=bool)
        w = 1.0 / var[keep]
        coef = nnls(design[keep] * w[:, None], y[keep] * w)[0]
        if not np.any(coef > 0):
            break
    return np.asarray(coef, dtype=np.float64)
