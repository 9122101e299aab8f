"""Keyframe headings made consistent by the images themselves (1-D rotation averaging).

A keyframe's map pose comes from SLAM. In a round room the laser cannot observe heading, so the
headings drift with the gyro and wheel odometry (a degree or two over a lap), and whatever error
a keyframe's heading carries goes straight into every heading later measured against it
(:mod:`symloc.vision.verification`). Two overlapping keyframes, though, give their relative
heading from the images alone. This module measures those relative headings and solves for
headings that agree with them, keeping SLAM's as a prior:

1. **Pairs** (:func:`candidate_pairs`). Keyframes within ``max_distance`` of each other whose
   SLAM headings differ by at most ``max_heading_difference`` (their fields of view overlap):
   the next ``trip_neighbours`` keyframes along the trip, and up to ``loop_pairs`` per keyframe
   of those far apart in the trip (loop closures: the pairs that tie the end of a lap to its
   start, which is where drift shows), nearest first.
2. **Relative headings** (:func:`measure_pairs`). Each pair's ORB matches are fitted by a
   planar motion (:func:`~symloc.vision.planar_motion.planar_yaw`: a level camera turning about
   the vertical and moving on the floor; curved walls and pure turns are no special case),
   searched within ``gate`` of SLAM's relative heading (SLAM drifts by degrees; a false match
   lands anywhere). A measurement counts with at least ``min_inliers`` inliers and a profile
   standard deviation of at most ``max_sigma`` (driving straight at a wall, a yaw error trades
   against the direction of travel and the images fix little). Its weight is
   ``hypot(profile sigma, measurement_sigma)``: the profile alone is optimistic (a simulated
   realistic camera's pairs are off by 0.2-0.7 degree median, more than their profiles say).
3. **Averaging** (:func:`solve_headings`). A factor graph on ``Rot2`` (GTSAM; angles wrap
   around): one prior per keyframe on its SLAM heading (``prior_sigma``: this fixes the gauge,
   so the map frame does not turn), one between-factor per consecutive pair along the trip with
   SLAM's relative heading (``chain_sigma``: locally the gyro is better than the images; a
   keyframe no image ties to follows its neighbours), and one Huber-robust between-factor per
   measured pair. Measured pairs whose residual exceeds ``outlier_threshold`` after a solve are
   dropped (the worst first) and the graph solved again, until none is.

With no measured pair every factor agrees with SLAM and the headings stay SLAM's. Positions are
not changed: a round room's SLAM positions turn about its centre with the heading drift, which
the images do not see (they fix relative headings only).

:func:`align_headings` runs the three steps on a list of keyframes (and gives keyframes with the
new headings, :meth:`HeadingAlignment.apply`); :func:`align_map_keyframes` on a visual map,
rewriting its keyframe headings in one transaction
(:meth:`~symloc.vision.visual_map.VisualMap.set_keyframe_headings`).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import gtsam
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from symloc._checks import check_integer, exact_real
from symloc.errors import ConfigurationError
from symloc.geometry import relative, wrap_angle
from symloc.vision.keyframes import Keyframe
from symloc.vision.orb import OrbFeatures
from symloc.vision.orientation import dist_coeffs_of, intrinsics_matrix
from symloc.vision.planar_motion import planar_yaw, travel_prior
from symloc.vision.two_view import ratio_matches, undistorted
from symloc.vision.visual_map import VisualMap

__all__ = [
    "HeadingAlignment",
    "HeadingAlignmentSettings",
    "PairMeasurements",
    "align_headings",
    "align_map_keyframes",
    "candidate_pairs",
    "measure_pairs",
    "solve_headings",
]

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: The visual map's ``meta`` key that records the last alignment of its keyframe headings.
META_KEY = "keyframe_headings"


@dataclass(frozen=True)
class HeadingAlignmentSettings:
    """Pairs, measurements and weights of the heading alignment (see the module docstring).

    Attributes
    ----------
    max_distance : float
        Pairs lie within this distance [m] of each other, > 0.
    max_heading_difference : float
        ... and their SLAM headings within this angle [rad], in (0, pi].
    trip_neighbours : int
        Each keyframe is paired with up to this many of the next keyframes along the trip, >= 0.
    loop_pairs : int
        Pairs per keyframe among those more than ``trip_neighbours`` keyframes apart along the
        trip (nearest first), >= 0.
    min_features : int
        Keyframes with fewer ORB features are not measured, >= 0.
    min_inliers : int
        Fewest inlier matches of a measurement that counts, >= 8.
    lowe_ratio : float
        Lowe's ratio of the ORB matching, in (0, 1).
    threshold : float
        Expected Sampson distance [px] of a correct match (the fit's truncation is 2.5 times
        it), > 0.
    gate : float
        The relative heading is searched within this angle [rad] of SLAM's, in (0, pi/2].
    position_sigma : float
        Standard deviation [m] of SLAM's relative position of trip neighbours, > 0: with the
        distance between them it gives the prior on the direction of travel of the fit.
    loop_position_sigma : float
        ... of a loop pair (drift accumulates around the loop), > 0.
    max_sigma : float
        Measurements whose profile standard deviation [rad] exceeds this are not used, > 0.
    measurement_sigma : float
        Standard deviation [rad] added (in quadrature) to each measurement's profile, > 0.
    prior_sigma : float
        Standard deviation [rad] of a SLAM heading as an absolute prior, > 0.
    chain_sigma : float
        Standard deviation [rad] of SLAM's relative heading between consecutive keyframes of
        the trip, > 0 (``inf``: no chain).
    huber_k : float
        Huber threshold of the measured pairs and of the chain, in standard deviations, > 0.
    outlier_threshold : float
        A measured pair whose residual [rad] exceeds this after a solve is dropped, > 0.
    max_rounds : int
        Most solves (each drops the worst outliers of the one before), >= 1.
    """

    max_distance: float = 1.5
    max_heading_difference: float = math.radians(30.0)
    trip_neighbours: int = 2
    loop_pairs: int = 4
    min_features: int = 50
    min_inliers: int = 40
    lowe_ratio: float = 0.8
    threshold: float = 1.0
    gate: float = math.radians(6.0)
    position_sigma: float = 0.02
    loop_position_sigma: float = 0.10
    max_sigma: float = math.radians(1.0)
    measurement_sigma: float = math.radians(0.5)
    prior_sigma: float = math.radians(3.0)
    chain_sigma: float = math.radians(0.1)
    huber_k: float = 1.0
    outlier_threshold: float = math.radians(1.5)
    max_rounds: int = 10

    def __post_init__(self) -> None:
        def check(name: str, ok: bool, what: str) -> None:
            if not ok:
                raise ConfigurationError(
                    f"HeadingAlignmentSettings.{name}: expected {what}, got {getattr(self, name)!r}"
                )

        def number(name: str) -> float:
            return exact_real(getattr(self, name))

        def integer(name: str, low: int) -> None:
            check_integer(getattr(self, name), f"HeadingAlignmentSettings.{name}", low)

        for name in (
            "max_distance",
            "position_sigma",
            "loop_position_sigma",
            "threshold",
            "max_sigma",
            "measurement_sigma",
            "prior_sigma",
            "huber_k",
            "outlier_threshold",
        ):
            v = number(name)
            check(name, math.isfinite(v) and v > 0, "a finite value > 0")
        check("chain_sigma", number("chain_sigma") > 0, "a value > 0 (inf: no chain)")
        v = number("max_heading_difference")
        check("max_heading_difference", 0 < v <= math.pi, "an angle in (0, pi] rad")
        check("gate", 0 < number("gate") <= math.pi / 2, "an angle in (0, pi/2] rad")
        check("lowe_ratio", 0.0 < number("lowe_ratio") < 1.0, "a value in (0, 1)")
        integer("trip_neighbours", 0)
        integer("loop_pairs", 0)
        integer("min_features", 0)
        integer("min_inliers", 8)
        integer("max_rounds", 1)


@dataclass(frozen=True)
class PairMeasurements:
    """Relative headings measured between keyframes.

    Attributes
    ----------
    pairs : (P, 2) int64
        Keyframe indices ``(i, j)`` of the measurements that count.
    yaws : (P,) float64
        Heading of ``j`` minus heading of ``i`` [rad], from the images.
    sigmas : (P,) float64
        Standard deviation [rad] each is weighted with.
    inliers : (P,) int64
        Inlier matches of each measurement.
    tried : int
        Pairs fitted (those that count and those refused).
    refused : dict of str to int
        Pairs refused, by reason (``"features"``: too few to try; ``"inliers"``; ``"sigma"``:
        the images do not fix the yaw).
    """

    pairs: IntArray
    yaws: FloatArray
    sigmas: FloatArray
    inliers: IntArray
    tried: int = 0
    refused: dict[str, int] = field(default_factory=dict)

    @classmethod
    def empty(cls) -> PairMeasurements:
        """No measurement."""
        return cls(np.zeros((0, 2), np.int64), np.zeros(0), np.zeros(0), np.zeros(0, np.int64))


@dataclass(frozen=True)
class HeadingAlignment:
    """The outcome of :func:`align_headings`.

    Attributes
    ----------
    headings : (N,) float64
        Aligned headings [rad], wrapped, in the keyframes' order.
    prior : (N,) float64
        The SLAM headings [rad] they started from.
    measurements : PairMeasurements
        Every measured pair that passed the checks of :func:`measure_pairs`.
    used : (P,) bool
        Which of them the solution kept (the others were outliers).
    residuals : (P,) float64
        Measured minus solved relative heading [rad] of each measured pair.
    rounds : int
        Solves run.
    seconds : float
        Wall time [s] of the whole alignment.
    """

    headings: FloatArray
    prior: FloatArray
    measurements: PairMeasurements
    used: NDArray[np.bool_]
    residuals: FloatArray
    rounds: int = 0
    seconds: float = 0.0

    @property
    def corrections(self) -> FloatArray:
        """Aligned minus SLAM heading [rad] per keyframe, (N,)."""
        return np.asarray(wrap_angle(self.headings - self.prior), np.float64)

    @property
    def tied(self) -> NDArray[np.bool_]:
        """Keyframes with at least one kept measured pair, (N,) bool."""
        out = np.zeros(self.headings.size, bool)
        out[self.measurements.pairs[self.used].ravel()] = True
        return out

    def apply(self, keyframes: Sequence[Keyframe]) -> list[Keyframe]:
        """``keyframes`` (the ones aligned, same order) with the aligned headings."""
        if len(keyframes) != self.headings.size:
            raise ConfigurationError(
                f"keyframes: {len(keyframes)} keyframes for {self.headings.size} aligned headings"
            )
        return [
            replace(kf, pose=np.array([kf.pose[0], kf.pose[1], h]))
            for kf, h in zip(keyframes, self.headings.tolist(), strict=True)
        ]

    def summary(self) -> str:
        """One line in words."""
        m = self.measurements
        corr = np.degrees(np.abs(self.corrections))
        refused = ", ".join(f"{k} {v}" for k, v in sorted(m.refused.items()) if v)
        return (
            f"keyframe headings: {int(self.used.sum())} of {m.pairs.shape[0]} image pairs kept "
            f"({m.tried} fitted{'; refused: ' + refused if refused else ''}), "
            f"{int(self.tied.sum())} of {self.headings.size} keyframes tied; heading changed by "
            f"mean {corr.mean() if corr.size else 0.0:.2f} deg, max "
            f"{corr.max() if corr.size else 0.0:.2f} deg ({self.seconds:.1f} s)"
        )


def _poses(poses: ArrayLike) -> FloatArray:
    p = np.asarray(poses, np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or not np.all(np.isfinite(p)):
        raise ConfigurationError(f"poses: expected an (N, 3) array of finite values, got {p.shape}")
    return p


def candidate_pairs(poses: ArrayLike, settings: HeadingAlignmentSettings | None = None) -> IntArray:
    """Pairs of keyframes whose views should overlap, by their SLAM poses.

    Parameters
    ----------
    poses : (N, 3) array
        Map poses (x [m], y [m], theta [rad]) in trip order.
    settings : HeadingAlignmentSettings, optional

    Returns
    -------
    (P, 2) int64
        ``(i, j)`` with ``i < j``: the trip neighbours first, then the loop pairs, nearest
        (distance over ``max_distance`` plus heading difference over
        ``max_heading_difference``) first.
    """
    s = settings if settings is not None else HeadingAlignmentSettings()
    p = _poses(poses)
    n = p.shape[0]
    if n < 2:
        return np.zeros((0, 2), np.int64)
    found = cKDTree(p[:, :2]).query_pairs(s.max_distance, output_type="ndarray")
    cand = np.sort(np.asarray(found, np.int64).reshape(-1, 2), axis=1)
    dth = np.abs(np.asarray(wrap_angle(p[cand[:, 1], 2] - p[cand[:, 0], 2]), np.float64))
    cand = cand[dth <= s.max_heading_difference]
    dth = dth[dth <= s.max_heading_difference]
    dist = np.hypot(*(p[cand[:, 1], :2] - p[cand[:, 0], :2]).T)
    cost = dist / s.max_distance + dth / s.max_heading_difference
    gap = cand[:, 1] - cand[:, 0]
    near = gap <= s.trip_neighbours
    trip = cand[near][np.lexsort((gap[near], cand[near][:, 0]))]
    loop_idx = np.flatnonzero(~near)
    loop_idx = loop_idx[np.argsort(cost[loop_idx], kind="stable")]
    count = np.zeros(n, np.int64)
    keep: list[int] = []
    if s.loop_pairs > 0:
        for k in loop_idx.tolist():
            i, j = cand[k]
            if count[i] < s.loop_pairs and count[j] < s.loop_pairs:
                keep.append(k)
                count[i] += 1
                count[j] += 1
    out: IntArray = np.concatenate([trip, cand[np.asarray(keep, np.int64)]]).reshape(-1, 2)
    return out


def measure_pairs(
    features: Sequence[OrbFeatures],
    poses: ArrayLike,
    pairs: ArrayLike,
    intrinsics: ArrayLike | object,
    settings: HeadingAlignmentSettings | None = None,
    *,
    dist_coeffs: ArrayLike | None = None,
) -> PairMeasurements:
    """Measure the relative heading of each pair from its two images.

    Parameters
    ----------
    features : sequence of N OrbFeatures
        The keyframes' ORB features (keypoints as the camera gave them; undistorted here).
    poses : (N, 3) array
        Their SLAM map poses (to predict the travel between a pair and gate the result).
    pairs : (P, 2) int array
        Indices ``(i, j)`` to measure (:func:`candidate_pairs`).
    intrinsics : (3, 3) array or camera object
    settings : HeadingAlignmentSettings, optional
    dist_coeffs : sequence of 4 or 5 floats, optional
        Lens distortion (default: ``intrinsics.dist_coeffs`` if any).
    """
    s = settings if settings is not None else HeadingAlignmentSettings()
    p = _poses(poses)
    if len(features) != p.shape[0]:
        raise ConfigurationError(f"features: {len(features)} keyframes for {p.shape[0]} poses")
    pr = np.asarray(pairs, np.int64).reshape(-1, 2)
    if pr.size and (pr.min() < 0 or pr.max() >= p.shape[0]):
        raise ConfigurationError(f"pairs: indices outside 0..{p.shape[0] - 1}")
    K = intrinsics_matrix(intrinsics)
    dist = dist_coeffs_of(intrinsics, dist_coeffs)
    und: dict[int, OrbFeatures] = {}

    def feats(i: int) -> OrbFeatures:
        if i not in und:
            und[i] = undistorted(features[i], K, dist)
        return und[i]

    # SLAM's relative pose of each pair: its heading is the centre of the search; the direction
    # of travel in the stored camera's frame (x right, z forward; t = -R c, c the query
    # camera's centre) a prior, as sure as SLAM's relative position over the distance
    rel = np.asarray(relative(p[pr[:, 0]], p[pr[:, 1]]), np.float64).reshape(-1, 3)
    expected = rel[:, 2]
    pos_sd = np.where(
        np.abs(pr[:, 1] - pr[:, 0]) <= s.trip_neighbours, s.position_sigma, s.loop_position_sigma
    )
    travel, travel_sd = travel_prior(rel, pos_sd)
    refused = {"features": 0, "inliers": 0, "sigma": 0}
    kept: list[tuple[int, int, float, float, int]] = []
    for (i, j), y0, ph0, ph_sd in zip(
        pr.tolist(), expected.tolist(), travel.tolist(), travel_sd.tolist(), strict=True
    ):
        if min(len(features[i]), len(features[j])) < max(s.min_features, 2):
            refused["features"] += 1
            continue
        src, dst = ratio_matches(feats(j), feats(i), s.lowe_ratio)
        fit = planar_yaw(
            src,
            dst,
            K,
            y0,
            s.gate,
            threshold=s.threshold,
            min_matches=s.min_inliers,
            direction=ph0,
            direction_sigma=ph_sd,
        )
        if not fit.fitted or fit.inliers < s.min_inliers:
            refused["inliers"] += 1
        elif not fit.sigma <= s.max_sigma:
            refused["sigma"] += 1
        else:
            sigma = math.hypot(fit.sigma, s.measurement_sigma)
            kept.append((i, j, float(wrap_angle(fit.yaw)), sigma, fit.inliers))
    tried = int(pr.shape[0]) - refused["features"]
    log.debug("measured %d of %d pairs (refused: %s)", len(kept), pr.shape[0], refused)
    if not kept:
        return replace(PairMeasurements.empty(), tried=tried, refused=refused)
    return PairMeasurements(
        pairs=np.array([k[:2] for k in kept], np.int64).reshape(-1, 2),
        yaws=np.array([k[2] for k in kept], np.float64),
        sigmas=np.array([k[3] for k in kept], np.float64),
        inliers=np.array([k[4] for k in kept], np.int64),
        tried=tried,
        refused=refused,
    )


def _solve_once(
    prior: FloatArray,
    pairs: IntArray,
    yaws: FloatArray,
    sigmas: FloatArray,
    s: HeadingAlignmentSettings,
) -> FloatArray:
    """One robust least-squares solve on Rot2 (see the module docstring)."""
    n = prior.size
    graph = gtsam.NonlinearFactorGraph()
    values = gtsam.Values()
    prior_noise = gtsam.noiseModel.Isotropic.Sigma(1, s.prior_sigma)
    for i, h in enumerate(prior.tolist()):
        values.insert(i, gtsam.Rot2(h))
        graph.add(gtsam.PriorFactorRot2(i, gtsam.Rot2(h), prior_noise))
    huber = gtsam.noiseModel.mEstimator.Huber.Create(s.huber_k)
    if math.isfinite(s.chain_sigma) and n > 1:
        # robust too: SLAM's heading can jump between two keyframes (a slip, a bad match)
        chain_noise = gtsam.noiseModel.Robust.Create(
            huber, gtsam.noiseModel.Isotropic.Sigma(1, s.chain_sigma)
        )
        steps = np.asarray(wrap_angle(np.diff(prior)), np.float64)
        for i, d in enumerate(steps.tolist()):
            graph.add(gtsam.BetweenFactorRot2(i, i + 1, gtsam.Rot2(d), chain_noise))
    for (i, j), y, sd in zip(pairs.tolist(), yaws.tolist(), sigmas.tolist(), strict=True):
        noise = gtsam.noiseModel.Robust.Create(huber, gtsam.noiseModel.Isotropic.Sigma(1, sd))
        graph.add(gtsam.BetweenFactorRot2(i, j, gtsam.Rot2(y), noise))
    params = gtsam.LevenbergMarquardtParams()
    params.setMaxIterations(100)
    params.setRelativeErrorTol(1e-10)
    params.setAbsoluteErrorTol(1e-12)
    result = gtsam.LevenbergMarquardtOptimizer(graph, values, params).optimize()
    return np.array([result.atRot2(i).theta() for i in range(n)], np.float64)


def _residuals(headings: FloatArray, pairs: IntArray, yaws: FloatArray) -> FloatArray:
    if pairs.shape[0] == 0:
        return np.zeros(0)
    solved = headings[pairs[:, 1]] - headings[pairs[:, 0]]
    return np.asarray(wrap_angle(yaws - solved), np.float64)


def solve_headings(
    prior: ArrayLike,
    pairs: ArrayLike,
    yaws: ArrayLike,
    settings: HeadingAlignmentSettings | None = None,
    *,
    sigmas: ArrayLike | None = None,
) -> tuple[FloatArray, NDArray[np.bool_], int]:
    """Headings that agree with the measured relative headings and, weakly, with ``prior``.

    Parameters
    ----------
    prior : (N,) array
        SLAM headings [rad] in trip order (consecutive ones are chained).
    pairs : (P, 2) int array
        Keyframe indices ``(i, j)`` of the measurements.
    yaws : (P,) array
        Measured heading of ``j`` minus heading of ``i`` [rad].
    settings : HeadingAlignmentSettings, optional
    sigmas : (P,) array, optional
        Standard deviation [rad] of each measurement (default: ``measurement_sigma``).

    Returns
    -------
    headings : (N,) float64
        Solved headings [rad], wrapped.
    used : (P,) bool
        The measurements kept (the others' residuals exceeded ``outlier_threshold``).
    rounds : int
        Solves run.
    """
    s = settings if settings is not None else HeadingAlignmentSettings()
    pr = np.asarray(prior, np.float64).reshape(-1)
    if not np.all(np.isfinite(pr)):
        raise ConfigurationError("prior: expected finite headings")
    pa = np.asarray(pairs, np.int64).reshape(-1, 2)
    ya = np.asarray(yaws, np.float64).reshape(-1)
    if ya.size != pa.shape[0] or not np.all(np.isfinite(ya)):
        raise ConfigurationError(f"yaws: expected {pa.shape[0]} finite relative headings")
    if pa.size and (pa.min() < 0 or pa.max() >= pr.size or np.any(pa[:, 0] == pa[:, 1])):
        raise ConfigurationError(f"pairs: expected two different indices in 0..{pr.size - 1}")
    sd = (
        np.full(ya.size, s.measurement_sigma)
        if sigmas is None
        else np.asarray(sigmas, np.float64).reshape(-1)
    )
    if sd.size != ya.size or not np.all(np.isfinite(sd) & (sd > 0)):
        raise ConfigurationError(f"sigmas: expected {ya.size} standard deviations > 0")
    used = np.ones(pa.shape[0], bool)
    headings = np.asarray(wrap_angle(pr), np.float64)
    if pr.size == 0:
        return headings, used, 0
    rounds = 0
    while True:
        solved = _solve_once(pr, pa[used], ya[used], sd[used], s)
        headings = np.asarray(wrap_angle(solved), np.float64)
        rounds += 1
        res = np.abs(_residuals(headings, pa, ya))
        bad = used & (res > s.outlier_threshold)
        if not bad.any() or rounds >= s.max_rounds:
            break
        # drop the worst outliers only: one bad pair can pull good neighbours over the threshold
        worst = float(res[bad].max())
        drop = bad & (res >= max(s.outlier_threshold, 0.5 * worst))
        used &= ~drop
        log.debug("heading alignment round %d: dropped %d pair(s)", rounds, int(drop.sum()))
    return headings, used, rounds


def align_headings(
    keyframes: Sequence[Keyframe],
    intrinsics: ArrayLike | object,
    settings: HeadingAlignmentSettings | None = None,
    *,
    dist_coeffs: ArrayLike | None = None,
) -> HeadingAlignment:
    """Align the headings of ``keyframes`` (in trip order) with their images.

    Parameters
    ----------
    keyframes : sequence of N Keyframe
        In trip order (the order they were recorded: consecutive ones are chained).
    intrinsics : (3, 3) array or camera object (e.g. :class:`~symloc.camera_model.CameraModel`)
    settings : HeadingAlignmentSettings, optional
    dist_coeffs : sequence of 4 or 5 floats, optional
        Lens distortion (default: ``intrinsics.dist_coeffs`` if any).

    Returns
    -------
    HeadingAlignment
        :meth:`HeadingAlignment.apply` gives the keyframes with the aligned headings.
    """
    t0 = time.perf_counter()
    s = settings if settings is not None else HeadingAlignmentSettings()
    poses = np.array([kf.pose for kf in keyframes], np.float64).reshape(-1, 3)
    pairs = candidate_pairs(poses, s)
    meas = measure_pairs(
        [kf.features for kf in keyframes], poses, pairs, intrinsics, s, dist_coeffs=dist_coeffs
    )
    headings, used, rounds = solve_headings(
        poses[:, 2], meas.pairs, meas.yaws, s, sigmas=meas.sigmas
    )
    out = HeadingAlignment(
        headings=headings,
        prior=np.asarray(wrap_angle(poses[:, 2]), np.float64),
        measurements=meas,
        used=used,
        residuals=_residuals(headings, meas.pairs, meas.yaws),
        rounds=rounds,
        seconds=time.perf_counter() - t0,
    )
    log.info("%s", out.summary())
    return out


def align_map_keyframes(
    visual_map: VisualMap,
    intrinsics: ArrayLike | object,
    settings: HeadingAlignmentSettings | None = None,
    *,
    dist_coeffs: ArrayLike | None = None,
    write: bool = True,
) -> HeadingAlignment:
    """Align the headings of a visual map's keyframes (in id order, the order of the trip).

    With ``write`` the new headings replace the stored ones in one transaction, with a note in
    the map's ``meta`` table (key :data:`META_KEY`); a crash leaves the old headings.
    """
    keyframes = visual_map.keyframes()
    result = align_headings(keyframes, intrinsics, settings, dist_coeffs=dist_coeffs)
    if write and keyframes:
        visual_map.set_keyframe_headings(
            [kf.keyframe_id for kf in keyframes],
            result.headings,
            meta={META_KEY: result.summary()},
        )
    return result
