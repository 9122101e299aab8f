"""A round room's keyframe headings: the gyro's, with its drift fitted to the images.

In a round room laser SLAM observes no heading: the scan matcher's cost is flat along a turn
about the room's centre, so SLAM's keyframe headings wander by one to three degrees from one
keyframe to the next (dev circle#1, realistic sensors: std 0.9 deg, up to 3.7 deg, and no
smooth model explains them: 0.75 deg left after fitting one). The mapping robot's
gyro-odometry drifts far more, 18 deg over that 200 s trip, but smoothly: after its start-up
calibration a MEMS gyro keeps a residual bias ``b`` and scale error ``s`` (the Kobuki's
ST L3G4200D: a bias drift of 0.03 deg/s per degC, non-linearity 0.2 %), so its heading error is

    ``odom_i - true_i = g + b t_i + s U_i + w_i``,

with ``t_i`` the time and ``U_i`` the angle turned since the start (unwrapped), and ``w_i`` the
angle random walk of its rate noise (0.03 deg/s/sqrt(Hz)). On that trip the three terms leave
0.14 deg std, 0.30 deg at most, when fitted to the truth.

Image pairs (:func:`symloc.vision.rotation_averaging.candidate_pairs` and
:func:`~symloc.vision.rotation_averaging.measure_pairs`) measure relative headings ``y_ij``
without the truth; each is one linear equation in ``b`` and ``s``:

    ``wrap(odom_j - odom_i - y_ij) = b (t_j - t_i) + s (U_j - U_i) + e_ij``.

:func:`fit_drift` solves them by weighted least squares with the gyro's data sheet as a prior
(``b`` and ``s`` zero-mean with the residual bias and scale stds of
:class:`DriftSettings`), dropping the worst pair while any residual exceeds
``outlier_threshold``. Without the prior a short trip's few pairs could leave the scale all
but free: test circle#1000000 (10 m^2, one lap, 16 pairs) fitted a 1.9 % scale where the
gyro's is 0.2 %, with a 4.3 deg heading std. Pairs far apart along the trip fix the bias;
pairs either side of a turn in place fix the scale. The gauge ``g`` (the map frame's
rotation, which the images cannot see) is set so that the new headings agree on average with
SLAM's of the keyframes that define the map (the trip SLAM drew it from), weighed by their
squared distance from the centre (:func:`round_room_keyframes`): the map keeps SLAM's frame.

:func:`round_room_keyframes` gives the keyframes with these headings, each position turned
about the room's centre by its change of heading (a round room's SLAM pose error is such a
turn), and :attr:`DriftFit.heading_std`, what the claim gate needs as the map's rotation error
(:attr:`symloc.localizer.claim.ClaimConfig.map_rotation_std`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_integer, exact_real
from symloc.errors import ConfigurationError
from symloc.geometry import turn_about, wrap_angle
from symloc.vision.keyframes import Keyframe
from symloc.vision.rotation_averaging import (
    HeadingAlignmentSettings,
    PairMeasurements,
    candidate_pairs,
    measure_pairs,
)
from symloc.vision.visual_map import VisualMap

__all__ = [
    "META_KEY",
    "POSITION_META_KEY",
    "DriftFit",
    "DriftSettings",
    "declared_position_std",
    "declared_rotation_std",
    "declared_round_map_error",
    "fit_drift",
    "round_room_keyframes",
]

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

#: The visual map's ``meta`` key holding :attr:`DriftFit.heading_std` [rad] of its keyframes.
META_KEY = "map_rotation_std"
#: The visual map's ``meta`` key holding :attr:`DriftFit.position_std` [m].
POSITION_META_KEY = "map_position_std"


@dataclass(frozen=True)
class DriftSettings:
    """How the drift is fitted and how sure the result is (see the module docstring).

    Attributes
    ----------
    rate_noise_density : float
        The gyro's rate noise density [rad/s/sqrt(Hz)], >= 0 (default: 0.03 deg/s/sqrt(Hz),
        the ST L3G4200D data sheet, Doc ID 17116, Table 4). Its angle random walk, which no
        smooth model removes, is counted in :attr:`DriftFit.heading_std`.
    outlier_threshold : float
        A pair whose residual [rad] exceeds this after a fit is dropped (the worst first), > 0.
    min_pairs : int
        Fewer measured pairs left: no fit, >= 3.
    max_pairs : int
        Most pairs measured, >= ``min_pairs``: two unknowns need few, and a large room's trip
        offers thousands (each costs a planar-motion fit, tens of ms). Beyond it the pairs
        farthest apart along the trip are kept (they fix the bias best).
    gauge_decorrelation : float
        SLAM's heading errors in a round room decorrelate over about this time [s], > 0: the
        gauge, a mean over keyframes of the new heading minus SLAM's, counts one independent
        sample per this time of the trip.
    bias_std : float
        The gyro's residual bias after its start-up calibration [rad/s] (std), the fit's prior
        on ``b``; 0 leaves the prior out. Default: the L3G4200D's zero-rate drift with
        temperature, 0.03 deg/s/degC over a 2 degC change during the trip (data sheet
        Table 4, as :data:`symloc.sim.gyro.L3G4200D`).
    scale_std : float
        Its residual scale error (a fraction, std), the prior on ``s``; 0 leaves it out.
        Default: the L3G4200D's non-linearity, 0.2 % (data sheet Table 4).
    """

    rate_noise_density: float = math.radians(0.03)
    outlier_threshold: float = math.radians(1.5)
    min_pairs: int = 10
    max_pairs: int = 300
    gauge_decorrelation: float = 10.0
    bias_std: float = math.radians(0.06)
    scale_std: float = 0.002

    def __post_init__(self) -> None:
        for name, low, strict in (
            ("rate_noise_density", 0.0, False),
            ("bias_std", 0.0, False),
            ("scale_std", 0.0, False),
            ("outlier_threshold", 0.0, True),
            ("gauge_decorrelation", 0.0, True),
        ):
            v = exact_real(getattr(self, name))
            if not (math.isfinite(v) and (v > low if strict else v >= low)):
                raise ConfigurationError(
                    f"DriftSettings.{name}: expected a finite value {'>' if strict else '>='} "
                    f"{low:g}, got {getattr(self, name)!r}"
                )
        check_integer(self.min_pairs, "DriftSettings.min_pairs", 3)
        check_integer(self.max_pairs, "DriftSettings.max_pairs", max(3, self.min_pairs))


@dataclass(frozen=True)
class DriftFit:
    """The gyro's fitted drift and the headings it gives.

    Attributes
    ----------
    bias : float
        Residual bias [rad/s].
    scale : float
        Residual scale error (a fraction of the angle turned).
    gauge : float
        Constant offset [rad] (the map frame's rotation, from SLAM's headings).
    covariance : (2, 2) float64
        Covariance of ``(bias, scale)`` given the pairs and the data sheet's prior, scaled by
        the residuals' chi-square per degree of freedom when that exceeds 1.
    headings : (N,) float64
        The keyframes' new headings [rad], wrapped.
    used : (P,) bool
        The measured pairs kept.
    residuals : (P,) float64
        Each pair's residual [rad] under the fit.
    heading_std : float
        Standard deviation [rad] of a new heading's error: the fit's worst keyframe, the
        gauge's and the gyro's angle random walk over half the trip, together.
    origin : float
        The gyro's (continuous) heading [rad] at the first keyframe, where the angle turned
        is counted from.
    position_std : float
        How far [m] (RMS) SLAM's trip was off along the wall, beyond one turn of the whole:
        each anchor keyframe's change of heading times its distance from the centre, less
        the best single turn (:func:`round_room_keyframes`; NaN: not computed). A round
        room's scans fix the distance from the centre, not the turn about it, so SLAM's
        trip is as wrong along the wall as its headings are, and the map drawn from it is
        placed no better than that; the map's own error estimate
        (:mod:`symloc.slam.map_error`) cannot see it (dev circle#0, 166 m^2: 14.2 cm mean
        trip error against a 2.0 cm estimate; this gives 10-15 cm, circle#1 1.5 cm).
    """

    bias: float
    scale: float
    gauge: float
    covariance: FloatArray
    headings: FloatArray
    used: NDArray[np.bool_]
    residuals: FloatArray
    heading_std: float
    origin: float = 0.0
    position_std: float = math.nan

    def correct(self, odom_headings: ArrayLike, stamps: ArrayLike) -> FloatArray:
        """Headings [rad] (wrapped) for gyro-odometry headings ``odom_headings`` (M,) [rad],
        continuous with the ones fitted (not wrapped between them), taken at ``stamps`` (M,)
        [s] of the same trip: e.g. images that are not keyframes."""
        odom = _vector(odom_headings, "odom_headings")
        t = _vector(stamps, "stamps", odom.size)
        raw = _without_drift(odom, t, self.bias, self.scale, self.origin)
        return np.asarray(wrap_angle(raw - self.gauge), np.float64)

    def summary(self) -> str:
        """One line in words."""
        return (
            f"round-room keyframe headings from gyro-odometry: drift fitted to "
            f"{int(self.used.sum())} of {self.used.size} image pairs, bias "
            f"{math.degrees(self.bias):+.4f} deg/s, scale {100 * self.scale:+.3f} %, heading std "
            f"{math.degrees(self.heading_std):.2f} deg"
            + (
                f", SLAM's trip {100 * self.position_std:.1f} cm (RMS) off along the wall"
                if math.isfinite(self.position_std)
                else ""
            )
        )


def _vector(v: ArrayLike, name: str, n: int | None = None) -> FloatArray:
    a = np.asarray(v, np.float64).reshape(-1)
    if (n is not None and a.size != n) or not np.all(np.isfinite(a)):
        want = f"{n} " if n is not None else ""
        raise ConfigurationError(f"{name}: expected {want}finite values, got shape {a.shape}")
    return a


def _without_drift(
    odom: FloatArray, stamps: FloatArray, bias: float, scale: float, origin: float
) -> FloatArray:
    """Gyro headings (continuous) less the drift ``bias t + scale (odom - origin)``, before
    the gauge."""
    return odom - bias * stamps - scale * (odom - origin)


def fit_drift(
    odom_headings: ArrayLike,
    stamps: ArrayLike,
    slam_headings: ArrayLike,
    measurements: PairMeasurements,
    settings: DriftSettings | None = None,
    *,
    gauge_weights: ArrayLike | None = None,
) -> DriftFit | None:
    """Fit the gyro's bias and scale error to measured relative headings.

    Parameters
    ----------
    odom_headings : (N,) array
        Gyro-odometry heading [rad] at each keyframe, in trip order, continuous (not wrapped:
        a turn in place between two keyframes can exceed half a turn).
    stamps : (N,) array
        Their times [s] on the trip.
    slam_headings : (N,) array
        SLAM's headings [rad] (the gauge: the new headings agree with them on average).
    measurements : PairMeasurements
        Relative headings measured between keyframes (indices into the N).
    settings : DriftSettings, optional
    gauge_weights : (N,) array, optional
        Weight (>= 0, some > 0) of each keyframe's SLAM heading in the gauge, a weighted mean
        (default: equal).

    Returns
    -------
    DriftFit or None
        None when fewer than ``min_pairs`` pairs are left or they do not fix both terms.
    """
    s = settings if settings is not None else DriftSettings()
    odom = _vector(odom_headings, "odom_headings")
    n = odom.size
    t = _vector(stamps, "stamps", n)
    slam = _vector(slam_headings, "slam_headings", n)
    pairs = np.asarray(measurements.pairs, np.int64).reshape(-1, 2)
    if pairs.size and (pairs.min() < 0 or pairs.max() >= n):
        raise ConfigurationError(f"measurements.pairs: indices outside 0..{n - 1}")
    turned = odom - odom[0] if n else odom
    i, j = pairs[:, 0], pairs[:, 1]
    design = np.column_stack([t[j] - t[i], turned[j] - turned[i]])
    target = np.asarray(wrap_angle(odom[j] - odom[i] - measurements.yaws), np.float64)
    weights = 1.0 / np.square(np.asarray(measurements.sigmas, np.float64))
    # the data sheet's prior: b, s ~ N(0, std^2), information added to the pairs'
    prior = np.diag([1.0 / v**2 if v > 0.0 else 0.0 for v in (s.bias_std, s.scale_std)]).astype(
        np.float64
    )
    used = np.ones(pairs.shape[0], bool)
    while True:
        if int(used.sum()) < s.min_pairs:
            return None
        a, y, w = design[used], target[used], weights[used]
        normal = a.T @ (a * w[:, None]) + prior
        if np.linalg.cond(normal) > 1e12:
            return None
        coef = np.linalg.solve(normal, a.T @ (w * y))
        res = target - design @ coef
        bad = used & (np.abs(res) > s.outlier_threshold)
        if not bad.any():
            break
        used[int(np.argmax(np.where(bad, np.abs(res), -1.0)))] = False
    dof = max(int(used.sum()) - 2, 1)
    chi2 = float(np.sum(weights[used] * res[used] ** 2)) / dof
    cov = np.linalg.inv(normal) * max(chi2, 1.0)
    raw = _without_drift(odom, t, float(coef[0]), float(coef[1]), float(odom[0]))
    w = np.ones(n) if gauge_weights is None else _vector(gauge_weights, "gauge_weights", n)
    if np.any(w < 0) or not np.any(w > 0):
        raise ConfigurationError("gauge_weights: expected weights >= 0, some > 0")
    w = w / w.sum()
    mask = w > 0
    offsets = np.asarray(wrap_angle(raw - slam), np.float64)
    gauge = float(math.atan2(w @ np.sin(offsets), w @ np.cos(offsets)))
    headings = np.asarray(wrap_angle(raw - gauge), np.float64)
    # the fit's uncertainty at each keyframe, about the gauge (the weighted mean)
    basis = np.column_stack([t, turned])
    centred = basis - w @ basis
    fit_var = float(np.max(np.einsum("ni,ij,nj->n", centred, cov, centred)))
    spread = np.asarray(wrap_angle(offsets - gauge), np.float64)
    duration = float(t.max() - t.min())
    anchored = float(t[mask].max() - t[mask].min())
    independent = max(1.0, anchored / s.gauge_decorrelation)
    gauge_var = float(w @ spread**2) / independent
    walk_var = s.rate_noise_density**2 * duration / 4.0
    std = math.sqrt(fit_var + gauge_var + walk_var)
    return DriftFit(
        bias=float(coef[0]),
        scale=float(coef[1]),
        gauge=gauge,
        covariance=np.asarray(cov, np.float64),
        headings=headings,
        used=used,
        residuals=np.asarray(res, np.float64),
        heading_std=std,
        origin=float(odom[0]),
    )


def round_room_keyframes(
    keyframes: Sequence[Keyframe],
    odom_headings: ArrayLike,
    centre: ArrayLike,
    intrinsics: ArrayLike | object,
    *,
    settings: DriftSettings | None = None,
    pairs: HeadingAlignmentSettings | None = None,
    dist_coeffs: ArrayLike | None = None,
    anchor: ArrayLike | None = None,
) -> tuple[list[Keyframe], DriftFit | None]:
    """A round room's keyframes with their headings from the gyro's fitted drift.

    Parameters
    ----------
    keyframes : sequence of N Keyframe
        In trip order, with SLAM's poses and their trip times (``stamp``).
    odom_headings : (N,) array
        Gyro-odometry heading [rad] of each when it was taken, continuous (not wrapped).
    centre : (2,) array
        The room's centre [m] in the map frame
        (:func:`symloc.localizer.map_symmetry.round_centre`).
    intrinsics : (3, 3) array or camera object
    settings : DriftSettings, optional
    pairs : HeadingAlignmentSettings, optional
        Which pairs are measured and how (:func:`~symloc.vision.rotation_averaging
        .candidate_pairs`, :func:`~symloc.vision.rotation_averaging.measure_pairs`).
    dist_coeffs : sequence of 4 or 5 floats, optional
    anchor : (N,) bool array, optional
        The keyframes whose SLAM poses define the map frame (default: all): those of the trip
        SLAM drew the map from, not poses later placed in that map, whose turn about the
        centre nothing fixes. The gauge weighs each by its squared distance from the centre:
        there SLAM's heading error equals the turn of its position about the centre (dev
        circle#1: 0.13-0.19 deg apart, std), which is what defines the map frame; near the
        centre a scan fixes no heading at all.

    Returns
    -------
    keyframes : list of Keyframe
        With the new headings, each position turned about ``centre`` by its change of heading
        (unchanged when there is no fit).
    fit : DriftFit or None
        None when the images did not fix the drift.
    """
    kfs = list(keyframes)
    c = _vector(centre, "centre", 2)
    poses = np.array([kf.pose for kf in kfs], np.float64).reshape(-1, 3)
    odom = _vector(odom_headings, "odom_headings", len(kfs))
    s = settings if settings is not None else DriftSettings()
    ps = pairs if pairs is not None else HeadingAlignmentSettings()
    lever = np.sum(np.square(poses[:, :2] - c), axis=1)
    if anchor is not None:
        flags = np.asarray(anchor, bool).reshape(-1)
        if flags.size != lever.size:
            raise ConfigurationError(f"anchor: expected {lever.size} flags, got {flags.size}")
        lever = lever * flags
    # the search for each pair's relative heading is centred on SLAM's (off by a few degrees
    # here, within the search's gate), not the gyro's (off by up to its bias times the time
    # between the two keyframes)
    found = candidate_pairs(poses, ps)
    if found.shape[0] > s.max_pairs:
        gap = found[:, 1] - found[:, 0]
        found = found[np.sort(np.argsort(-gap, kind="stable")[: s.max_pairs])]
    meas = measure_pairs(
        [kf.features for kf in kfs], poses, found, intrinsics, ps, dist_coeffs=dist_coeffs
    )
    fit = fit_drift(odom, [kf.stamp for kf in kfs], poses[:, 2], meas, s, gauge_weights=lever)
    if fit is None:
        log.info("round-room keyframe headings: the images do not fix the gyro's drift")
        return kfs, None
    turn = np.asarray(wrap_angle(fit.headings - poses[:, 2]), np.float64)
    fit = replace(fit, position_std=_along_the_wall(turn, lever))
    xy = turn_about(poses, c, turn)[:, :2]
    out = [
        replace(kf, pose=np.array([x, y, h]))
        for kf, (x, y), h in zip(kfs, xy.tolist(), fit.headings.tolist(), strict=True)
    ]
    log.info("%s", fit.summary())
    return out, fit


def _along_the_wall(turn: FloatArray, lever: FloatArray) -> float:
    """RMS [m] of ``turn`` (N,) [rad] times the distance from the centre (``lever`` (N,) its
    square [m^2], 0 for keyframes left out), less the best single turn."""
    if not np.any(lever > 0.0):
        return math.nan
    common = float(np.sum(lever * turn) / np.sum(lever))
    return math.sqrt(float(np.sum(lever * np.square(turn - common)) / np.count_nonzero(lever)))


def declared_rotation_std(visual_map: VisualMap) -> float | None:
    """The rotation error [rad] (std) about a round map's centre that ``visual_map`` declares
    (its ``meta`` key :data:`META_KEY`, written where the mapping gyro's drift was fitted to
    the images: :attr:`DriftFit.heading_std`); None when it declares none.

    Raises
    ------
    ConfigurationError
        The value is not a finite positive number (naming the file and the key).
    """
    return _declared(visual_map, META_KEY, "angle [rad]")


def declared_position_std(visual_map: VisualMap) -> float | None:
    """How far [m] (std) a round map is placed as ``visual_map`` declares it (its ``meta`` key
    :data:`POSITION_META_KEY`: :attr:`DriftFit.position_std`, the trip SLAM drew the map
    from, off along the wall); None when it declares none. Raises as
    :func:`declared_rotation_std`."""
    return _declared(visual_map, POSITION_META_KEY, "distance [m]")


def declared_round_map_error(visual_map: VisualMap) -> tuple[float | None, float | None]:
    """The rotation error [rad] and position error [m] (stds) a round map's ``visual_map``
    declares (:func:`declared_rotation_std`, :func:`declared_position_std`), what
    :func:`symloc.localizer.build.build_localizer` takes as ``map_rotation_std`` and as a
    floor of ``map_std_xy``."""
    return declared_rotation_std(visual_map), declared_position_std(visual_map)


def _declared(visual_map: VisualMap, key: str, what: str) -> float | None:
    raw = visual_map.get_meta(key)
    if raw is None:
        return None
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value <= 0.0:
        raise ConfigurationError(
            f"{visual_map.path}: meta {key!r}: expected a finite positive {what} (std), got {raw!r}"
        )
    return value
