"""Noisy odometry from a reference trajectory (Thrun et al. 2005, Table 5.6, sample_motion_model).

Each increment between consecutive reference poses is decomposed into ``rot1, trans, rot2``
(:func:`symloc.odometry.rot_trans_rot`); a systematic calibration error scales them
(``trans * trans_scale``, ``rot1, rot2 * rot_scale``: a wrong mean wheel diameter and a wrong
wheel base, the two dominant systematic errors of differential-drive odometry in Borenstein &
Feng 1996, "Measurement and correction of systematic odometry errors in mobile robots", IEEE
T-RA 12(6)); then zero-mean Gaussian noise with variances

- ``rot1, rot2``: ``alpha1 * rot^2 + alpha2 * trans^2``
- ``trans``: ``alpha3 * trans^2 + alpha4 * (rot1^2 + rot2^2)``

is added (the model and parameter names of nav2_amcl's ``DifferentialMotionModel``; like it,
the rotations that enter the variances are taken modulo a half turn, so that driving backwards
does not count as two half turns). Increments shorter than ``in_place_below`` [m] count as
turns on the spot in the variances (``rot1 = 0``, the whole turn in ``rot2``): the corrected
CARMEN poses move the laser a few centimetres sideways while the robot turns, which would
otherwise give a meaningless direction of travel ``rot1`` of up to 180 degrees. The noisy
increments are then chained from the first reference pose (the motion itself is unchanged).

Two named regimes (:data:`ODOMETRY_REGIMES`), both applied to the scan-to-scan increments of
the reference (the corrected CARMEN poses, or the simulator's true poses):

- ``realistic``: calibration error distance x 1.015, rotations x 0.99 (1.5 % and 1 %:
  the order of magnitude issue 21 gives for an uncalibrated robot, 1-2 % in distance and 1 %
  in rotation; the error types are Borenstein & Feng's), plus
  small zero-mean noise ``alpha1..alpha4 = (0.0016, 0.0001, 0.0004, 0.0001)``, i.e. standard
  deviations of 4 % of each rotation plus 0.01 rad per metre driven, and 2 % of each
  distance plus 1 cm per radian turned. On the shared CARMEN logs (seed 0,
  :func:`increment_errors`) the error of one scan-to-scan increment is 1-2 cm and 0.6-0.8 deg at
  the median and 3-6 cm and 1.5-2.3 deg at the 90th percentile (freiburg-079, scanned four
  times as often, 0.2 cm and 0.1 deg): an order of magnitude below the heavy regime, as
  wheel odometry is from one scan to the next.
- ``heavy``: no calibration error and ``alpha1..alpha4 = (0.04, 0.01, 0.01, 0.04)``, GMapping's
  default odometry error parameters (``stt = 0.2, str = 0.1, srr = 0.1, srt = 0.2``, standard
  deviations per unit motion) squared into the variance coefficients of this model: a filter's
  deliberately inflated model used as the true noise: 0.10-0.14 m and 5-6 deg per scan at the
  median, 0.2-0.4 m and 12-16 deg at the 90th percentile. :data:`DEFAULT_ALPHAS` are its alphas.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import as_rng, check_array, check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import angle_diff, relative, wrap_angle
from symloc.odometry import rot_trans_rot, rot_trans_rot_to_pose

__all__ = [
    "DEFAULT_ALPHAS",
    "HEAVY",
    "ODOMETRY_REGIMES",
    "REALISTIC",
    "OdometryRegime",
    "increment_errors",
    "noisy_odometry",
    "regime_odometry",
]

#: alpha1..alpha4 of the ``heavy`` regime (rad^2/rad^2, rad^2/m^2, m^2/m^2, m^2/rad^2).
DEFAULT_ALPHAS = (0.04, 0.01, 0.01, 0.04)


@dataclass(frozen=True, slots=True)
class OdometryRegime:
    """A named odometry error model: calibration scales plus Thrun's zero-mean noise.

    Parameters
    ----------
    name : str
    alphas : tuple of 4 floats
        alpha1..alpha4 (>= 0) of the zero-mean noise (see the module docstring).
    trans_scale : float
        Factor on every translation (> 0; 1.015 reports 1.5 % too much distance).
    rot_scale : float
        Factor on every rotation (> 0).
    source : str
        Where the figures come from, for printing with the results.
    """

    name: str
    alphas: tuple[float, float, float, float]
    trans_scale: float = 1.0
    rot_scale: float = 1.0
    source: str = ""

    def __post_init__(self) -> None:
        if len(self.alphas) != 4:
            raise ConfigurationError("OdometryRegime.alphas: expected 4 values alpha1..alpha4")
        for k, a in enumerate(self.alphas):
            check_positive(a, f"OdometryRegime.alphas[{k}]", allow_zero=True)
        check_positive(self.trans_scale, "OdometryRegime.trans_scale")
        check_positive(self.rot_scale, "OdometryRegime.rot_scale")

    def describe(self) -> str:
        """One line: the figures of the regime."""
        cal = (
            f"distance x {self.trans_scale:g}, rotations x {self.rot_scale:g}, "
            if (self.trans_scale, self.rot_scale) != (1.0, 1.0)
            else "no calibration error, "
        )
        return f"{self.name}: {cal}alphas {tuple(self.alphas)}" + (
            f" ({self.source})" if self.source else ""
        )


#: Calibrated wheel odometry: small systematic error plus small noise (see module docstring).
REALISTIC = OdometryRegime(
    "realistic",
    (0.0016, 0.0001, 0.0004, 0.0001),
    trans_scale=1.015,
    rot_scale=0.99,
    source="systematic errors as Borenstein & Feng 1996; figures of issue 21",
)
#: GMapping's default filter noise used as the true noise.
HEAVY = OdometryRegime(
    "heavy", DEFAULT_ALPHAS, source="GMapping's default srr/srt/str/stt, squared"
)
#: The regimes by name.
ODOMETRY_REGIMES: dict[str, OdometryRegime] = {"realistic": REALISTIC, "heavy": HEAVY}


def noisy_odometry(
    reference: ArrayLike,
    alphas: tuple[float, float, float, float] = DEFAULT_ALPHAS,
    rng: np.random.Generator | int | None = None,
    *,
    in_place_below: float = 0.1,
    trans_scale: float = 1.0,
    rot_scale: float = 1.0,
) -> NDArray[np.float64]:
    """Odometry poses ``(N, 3)`` made by perturbing the increments of ``reference`` (N, 3).

    The first pose equals ``reference[0]``; ``alphas`` are the four odometry noise
    parameters (all >= 0); ``trans_scale`` and ``rot_scale`` the calibration factors.
    Deterministic for a given ``rng`` seed.
    """
    ref = check_array(reference, "reference", shape=(None, 3))
    for k, a in enumerate(alphas):
        check_positive(a, f"alphas[{k}]", allow_zero=True)
    if len(alphas) != 4:
        raise ValueError("alphas: expected 4 values alpha1..alpha4")
    gen = as_rng(rng)
    check_positive(trans_scale, "trans_scale")
    check_positive(rot_scale, "rot_scale")
    a1, a2, a3, a4 = (float(a) for a in alphas)
    r1, tr, r2 = rot_trans_rot(ref[:-1], ref[1:])
    n = r1.shape[0]
    spot = tr < in_place_below
    v1 = np.where(spot, 0.0, r1)
    v2 = np.where(spot, angle_diff(ref[1:, 2], ref[:-1, 2]), r2)
    q1 = np.minimum(np.abs(v1), np.pi - np.abs(v1))
    q2 = np.minimum(np.abs(v2), np.pi - np.abs(v2))
    sd_r1 = np.sqrt(a1 * q1**2 + a2 * tr**2)
    sd_tr = np.sqrt(a3 * tr**2 + a4 * (q1**2 + q2**2))
    sd_r2 = np.sqrt(a1 * q2**2 + a2 * tr**2)
    nr1 = r1 * rot_scale + gen.normal(size=n) * sd_r1
    ntr = tr * trans_scale + gen.normal(size=n) * sd_tr
    nr2 = r2 * rot_scale + gen.normal(size=n) * sd_r2
    out = np.empty_like(ref)
    out[0] = ref[0]
    for i in range(n):  # a chain: each pose depends on the previous one
        out[i + 1] = rot_trans_rot_to_pose(out[i], nr1[i], ntr[i], nr2[i])
    return out


def regime_odometry(
    reference: ArrayLike,
    regime: OdometryRegime | str,
    rng: np.random.Generator | int | None = None,
) -> NDArray[np.float64]:
    """Odometry ``(N, 3)`` for ``reference`` (N, 3) under a named regime (or its name).

    Raises
    ------
    ConfigurationError
        An unknown regime name.
    """
    if isinstance(regime, str):
        if regime not in ODOMETRY_REGIMES:
            raise ConfigurationError(
                f"odometry regime: expected one of {sorted(ODOMETRY_REGIMES)}, got {regime!r}"
            )
        regime = ODOMETRY_REGIMES[regime]
    return noisy_odometry(
        reference,
        regime.alphas,
        rng,
        trans_scale=regime.trans_scale,
        rot_scale=regime.rot_scale,
    )


def increment_errors(reference: ArrayLike, odometry: ArrayLike) -> dict[str, float]:
    """Per-increment odometry error statistics of ``odometry`` against ``reference`` (N, 3).

    Returns the median and 90th percentile of the translation error [m] and of the absolute
    heading error [deg] of each scan-to-scan increment (keys ``trans_median_m``,
    ``trans_p90_m``, ``rot_median_deg``, ``rot_p90_deg``).
    """
    ref = check_array(reference, "reference", shape=(None, 3))
    odo = check_array(odometry, "odometry", shape=ref.shape)
    e = relative(relative(ref[:-1], ref[1:]), relative(odo[:-1], odo[1:]))
    t = np.hypot(e[:, 0], e[:, 1])
    r = np.degrees(np.abs(wrap_angle(e[:, 2])))
    return {
        "trans_median_m": float(np.median(t)),
        "trans_p90_m": float(np.percentile(t, 90)),
        "rot_median_deg": float(np.median(r)),
        "rot_p90_deg": float(np.percentile(r, 90)),
    }
