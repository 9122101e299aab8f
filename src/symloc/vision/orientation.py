"""Orientation decision at a symmetric place (Algorithm 3 and step 7 of Algorithm 5).

A query image taken at the centre of a known place is scored against the place's M stored
images (BoW, DBoW2 scoring). A direction is decided only when

1. the query has enough keypoints (an almost empty BoW vector scores well against anything, so
   images with fewer than ``min_keypoints`` are *refused*);
2. the best score clearly beats the second: ``best >= min_score`` and
   ``best >= min_score_ratio * second``. Views of the same wall from the same spot score several
   times higher than views of different walls (the paper's Table 3: 0.91-0.96 against
   0.07-0.13, a ratio of about 7), while in a room that looks the same in every direction (the
   untextured lab) the M scores are nearly equal (ratio about 1). A ratio of 2 sits between the
   two with a wide margin on both sides, and does not depend on the scoring's scale;
3. the best direction survives geometric verification: ORB matches that pass Lowe's ratio test
   fit a homography with RANSAC (a camera turning in place sees a pure rotation
   ``H = K R K^-1``, for which a fundamental matrix is ill-conditioned) with at least
   ``min_inliers`` inliers, more than ``min_inlier_ratio`` times those of *every* other stored
   direction (all M are fitted, so a second view of the same scene is caught even when the BoW
   ranking put it far down), and the rotation it implies is a yaw of at most ``max_offset``
   with little roll/pitch.

With ``geometric_fallback`` (the default), a query whose BoW scores fail test 2 is not given up
at once: the direction with the most homography inliers is taken instead, under the same tests
of step 3. On real photographs a vocabulary trained on other images gives weak BoW scores (0.02
to 0.25 for a re-capture of the same view, against 0.91-0.96 in the paper's Table 3), while the
homography separates the right direction by an order of magnitude (dozens to hundreds of
inliers against at most about 12 for the other views); see :mod:`symloc.bench.photos`. Scenes
that look alike in two directions still fit both with similar inlier counts and stay
undetermined.

The residual heading offset (query heading minus stored heading, counter-clockwise positive) is
read from the homography's inliers (a rotation plus a small zoom fitted to them, or optionally
the rotation nearest to ``K^-1 H K``), so the decided heading is ``heading_j + offset``, continuous rather
than a multiple of 360/M.

A real lens bends straight lines, and a turn in place is a homography only between *ideal*
pinhole images. When the camera's distortion coefficients are given (``dist_coeffs``, or a
camera object such as :class:`symloc.camera_model.CameraModel` that carries them), the keypoint
positions of the query and of the stored images are undistorted (``cv2.undistortPoints``)
before the homography and the heading offset are fitted; the descriptors are unchanged. Without
coefficients (or all zero) the positions are used as they are. When the decision is not clear, the caller turns the robot clockwise
by 360/M and tries again (the paper's protocol), up to M times: see :func:`decide_with_retries`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.camera_model import check_dist_coeffs
from symloc.errors import ConfigurationError
from symloc.geometry import wrap_angle
from symloc.vision.bow import BowVector
from symloc.vision.orb import OrbExtractor, OrbFeatures
from symloc.vision.place import Place
from symloc.vision.two_view import ratio_matches, undistorted, yaw_and_tilt
from symloc.vision.vocabulary import Vocabulary

__all__ = [
    "OrientationConfig",
    "OrientationDecision",
    "decide_orientation",
    "decide_with_retries",
    "dist_coeffs_of",
    "intrinsics_matrix",
    "match_homography",
    "match_inliers",
    "rotation_from_correspondences",
    "yaw_from_homography",
]

Status = Literal["decided", "undetermined", "refused"]


@dataclass(frozen=True)
class OrientationConfig:
    """Thresholds of the orientation decision (see the module docstring for the reasoning).

    Attributes
    ----------
    min_keypoints : int
        Queries with fewer ORB keypoints are refused.
    min_score : float
        Lowest acceptable best BoW score (vocabulary scoring units; L1 scores lie in [0, 1]).
    min_score_ratio : float
        The best score must be at least this multiple of the second best (> 1).
    lowe_ratio : float
        Lowe's ratio test on the two nearest Hamming neighbours, in (0, 1).
    ransac_threshold : float
        RANSAC reprojection threshold [px].
    min_inliers : int
        Fewest homography inliers for a verified direction (>= 4).
    min_inlier_ratio : float
        Best direction's inliers must be at least this multiple of the second's.
    max_offset : float or None
        Largest accepted residual yaw [rad]; None means half a sector, pi / M.
    max_tilt : float
        Largest accepted roll/pitch [rad] of the homography's rotation.
    geometric_fallback : bool
        When the BoW scores are weak or ambiguous, decide by the homography inliers alone
        (direction with the most inliers, same ``min_inliers`` / ``min_inlier_ratio`` tests);
        False gives the paper's BoW-first rule (undetermined as soon as BoW is ambiguous).
    offset_from : {"rotation", "homography"}
        How the heading offset (and the tilt check) is read from the RANSAC inliers: a rotation
        plus zoom fitted to them (:func:`rotation_from_correspondences`, default), or the
        rotation nearest to ``K^-1 H K`` of the 8-DOF homography (:func:`yaw_from_homography`).
    """

    min_keypoints: int = 100
    min_score: float = 0.05
    min_score_ratio: float = 2.0
    lowe_ratio: float = 0.8
    ransac_threshold: float = 3.0
    min_inliers: int = 20
    min_inlier_ratio: float = 2.0
    max_offset: float | None = None
    max_tilt: float = math.radians(10.0)
    geometric_fallback: bool = True
    offset_from: str = "rotation"

    def __post_init__(self) -> None:
        if int(self.min_keypoints) != self.min_keypoints or self.min_keypoints < 1:
            raise ConfigurationError(
                f"min_keypoints: expected an integer >= 1, got {self.min_keypoints}"
            )
        if not (math.isfinite(self.min_score) and self.min_score >= 0):
            raise ConfigurationError(f"min_score: expected a value >= 0, got {self.min_score}")
        if not (math.isfinite(self.min_score_ratio) and self.min_score_ratio > 1.0):
            raise ConfigurationError(
                f"min_score_ratio: expected a value > 1, got {self.min_score_ratio}"
            )
        if not 0.0 < self.lowe_ratio < 1.0:
            raise ConfigurationError(
                f"lowe_ratio: expected a value in (0, 1), got {self.lowe_ratio}"
            )
        if not (math.isfinite(self.ransac_threshold) and self.ransac_threshold > 0):
            raise ConfigurationError(
                f"ransac_threshold: expected a value > 0 [px], got {self.ransac_threshold}"
            )
        if int(self.min_inliers) != self.min_inliers or self.min_inliers < 4:
            raise ConfigurationError(
                f"min_inliers: expected an integer >= 4, got {self.min_inliers}"
            )
        if not (math.isfinite(self.min_inlier_ratio) and self.min_inlier_ratio >= 1.0):
            raise ConfigurationError(
                f"min_inlier_ratio: expected a value >= 1, got {self.min_inlier_ratio}"
            )
        if self.max_offset is not None and not 0 < self.max_offset <= math.pi:
            raise ConfigurationError(
                f"max_offset: expected None or a value in (0, pi] [rad], got {self.max_offset}"
            )
        if self.offset_from not in ("rotation", "homography"):
            raise ConfigurationError(
                f"offset_from: expected 'rotation' or 'homography', got {self.offset_from!r}"
            )
        if not 0 < self.max_tilt <= math.pi:
            raise ConfigurationError(
                f"max_tilt: expected a value in (0, pi] [rad], got {self.max_tilt}"
            )


@dataclass(frozen=True)
class OrientationDecision:
    """The outcome of an orientation decision.

    Attributes
    ----------
    status : {"decided", "undetermined", "refused"}
    direction : int or None
        Clockwise index j of the stored image the robot faced (at the first attempt).
    heading_offset : float
        Query heading minus the stored heading of ``direction`` [rad], CCW positive (NaN when
        not decided).
    heading : float
        Decided map heading [rad] (stored heading + offset); NaN when not decided.
    scores : tuple of float
        BoW score against each of the M stored images (last attempt).
    best_score, second_score : float
    inliers, second_inliers : int
        Homography inliers for the best and the second-best direction.
    n_keypoints : int
        Keypoints in the (last) query image.
    attempts : int
        Images tried (1 without retries).
    reason : str
        Why, in words (directions numbered from 1, as people count them).
    """

    status: Status
    direction: int | None
    heading_offset: float
    heading: float
    scores: tuple[float, ...]
    best_score: float
    second_score: float
    inliers: int
    second_inliers: int
    n_keypoints: int
    reason: str
    attempts: int = 1
    homography: NDArray[np.float64] | None = field(default=None, repr=False)

    @property
    def decided(self) -> bool:
        """True when a direction was decided."""
        return self.status == "decided"


def intrinsics_matrix(intrinsics: ArrayLike | object) -> NDArray[np.float64]:
    """Return a 3x3 camera matrix from an array or an object with ``K``/``fx, fy, cx, cy``."""
    for attr in ("K", "matrix", "intrinsics"):
        if hasattr(intrinsics, attr):
            val = getattr(intrinsics, attr)
            intrinsics = val() if callable(val) else val
            break
    else:
        if all(hasattr(intrinsics, a) for a in ("fx", "fy", "cx", "cy")):
            o: Any = intrinsics
            intrinsics = [[o.fx, 0, o.cx], [0, o.fy, o.cy], [0, 0, 1]]
    K = np.asarray(intrinsics, np.float64)
    if K.shape != (3, 3) or not np.all(np.isfinite(K)) or K[0, 0] <= 0 or K[1, 1] <= 0:
        raise ConfigurationError(
            f"intrinsics: expected a 3x3 camera matrix with fx, fy > 0, got {K}"
        )
    return K


def dist_coeffs_of(
    intrinsics: ArrayLike | object, dist_coeffs: ArrayLike | None = None
) -> tuple[float, ...]:
    """Distortion coefficients ``(k1, k2, p1, p2, k3)``: ``dist_coeffs`` if given, else the
    camera object's ``dist_coeffs`` attribute, else none (all zero)."""
    if dist_coeffs is None:
        dist_coeffs = getattr(intrinsics, "dist_coeffs", None)
    return check_dist_coeffs(dist_coeffs)


def match_inliers(
    query: OrbFeatures, stored: OrbFeatures, config: OrientationConfig
) -> tuple[NDArray[np.float64] | None, NDArray[np.float64], NDArray[np.float64], int]:
    """Match ORB descriptors (Lowe ratio test) and fit ``stored -> query`` homography (RANSAC).

    Returns
    -------
    H : (3, 3) float64 or None
    src, dst : (n, 2) float64
        Stored and query pixel positions of the n RANSAC inliers.
    matches : int
        Matches that passed the ratio test.
    """
    none = np.zeros((0, 2))
    src, dst = ratio_matches(query, stored, config.lowe_ratio)
    if src.shape[0] < 4:
        return None, none, none, int(src.shape[0])
    H, mask = cv2.findHomography(src, dst, cv2.RANSAC, config.ransac_threshold)
    if H is None or mask is None:
        return None, none, none, int(src.shape[0])
    keep = mask.ravel().astype(bool)
    return np.asarray(H, np.float64), src[keep], dst[keep], int(src.shape[0])


def match_homography(
    query: OrbFeatures, stored: OrbFeatures, config: OrientationConfig
) -> tuple[NDArray[np.float64] | None, int, int]:
    """Match ORB descriptors (Lowe ratio test) and fit ``stored -> query`` homography (RANSAC).

    Returns
    -------
    H : (3, 3) float64 or None
    inliers : int
    matches : int
        Matches that passed the ratio test.
    """
    H, src, _, n = match_inliers(query, stored, config)
    return H, int(src.shape[0]), n


def rotation_from_correspondences(
    src: ArrayLike, dst: ArrayLike, K: ArrayLike, iterations: int = 3
) -> tuple[float, float, float]:
    """Yaw, tilt and zoom of ``dst ~ K R diag(z, z, 1) K^-1 src`` from inlier pixel pairs.

    The camera turned in place by ``R`` and the robot stood slightly nearer to or farther from
    a wall facing it (a zoom ``z`` about the principal point). ``R`` solves Wahba's problem on
    the unit bearing vectors (SVD), alternating with the least-squares ``z``. With 4 degrees of
    freedom instead of the homography's 8, the offset stays accurate when the inliers are few
    or cover a small part of the image (an occluded view), where reading the yaw from a full
    homography can be off by 10 degrees or more (see :mod:`symloc.bench.photos`).

    Parameters
    ----------
    src, dst : (n, 2) array, n >= 2
        Stored and query pixel positions [px].
    K : (3, 3) array
    iterations : int

    Returns
    -------
    yaw : float
        Query heading minus stored heading [rad], CCW positive.
    tilt : float
        Roll/pitch [rad] left after removing the yaw.
    zoom : float
        Scale of the query against the stored view (> 1: nearer).
    """
    a_px = np.asarray(src, np.float64).reshape(-1, 2)
    b_px = np.asarray(dst, np.float64).reshape(-1, 2)
    if a_px.shape[0] < 2 or b_px.shape != a_px.shape:
        return math.nan, math.nan, math.nan
    Kinv = np.linalg.inv(np.asarray(K, np.float64))
    a = np.column_stack([a_px, np.ones(len(a_px))]) @ Kinv.T
    b = np.column_stack([b_px, np.ones(len(b_px))]) @ Kinv.T
    bn = b / np.linalg.norm(b, axis=1, keepdims=True)
    z = 1.0
    R = np.eye(3)
    for _ in range(max(1, int(iterations))):
        da = a.copy()
        da[:, :2] *= z
        da /= np.linalg.norm(da, axis=1, keepdims=True)
        U, _, Vt = np.linalg.svd(bn.T @ da)
        R = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
        c = b @ R  # rows R^T b
        c = c[:, :2] / c[:, 2:3]
        den = float(np.sum(a[:, :2] ** 2))
        if den <= 0 or not np.isfinite(den):
            break
        z = float(np.sum(c * a[:, :2]) / den)
        if not (np.isfinite(z) and z > 0):
            return math.nan, math.nan, math.nan
    yaw, tilt = yaw_and_tilt(R)
    return yaw, tilt, z


def yaw_from_homography(H: ArrayLike, K: ArrayLike) -> tuple[float, float]:
    """Yaw and tilt of the rotation behind a pure-rotation homography ``H = K R K^-1``.

    Camera frame: x right, y down, z forward. ``H`` maps stored pixels to query pixels.

    Returns
    -------
    yaw : float
        Query heading minus stored heading [rad], counter-clockwise (robot turning left) positive.
    tilt : float
        Angle [rad] of the remaining rotation after removing the yaw (roll/pitch; ~0 for a
        robot turning in place).
    """
    Km = np.asarray(K, np.float64)
    R = np.linalg.inv(Km) @ np.asarray(H, np.float64) @ Km
    det = np.linalg.det(R)
    if not np.isfinite(det) or abs(det) < 1e-12:
        return math.nan, math.nan
    R = R / np.cbrt(det)
    U, _, Vt = np.linalg.svd(R)
    R = U @ Vt
    if np.linalg.det(R) < 0:
        R = -R
    return yaw_and_tilt(R)


def _undecided(
    status: Status, reason: str, scores: Sequence[float] | NDArray[Any], n_kp: int, **kw: int
) -> OrientationDecision:
    s = np.sort(np.asarray(scores, float))[::-1] if len(scores) else np.zeros(0)
    return OrientationDecision(
        status=status,
        direction=None,
        heading_offset=math.nan,
        heading=math.nan,
        scores=tuple(float(x) for x in scores),
        best_score=float(s[0]) if s.size else math.nan,
        second_score=float(s[1]) if s.size > 1 else math.nan,
        inliers=int(kw.get("inliers", 0)),
        second_inliers=int(kw.get("second_inliers", 0)),
        n_keypoints=n_kp,
        reason=reason,
    )


def decide_orientation(
    query: OrbFeatures | ArrayLike,
    place: Place,
    vocabulary: Vocabulary,
    intrinsics: ArrayLike | object,
    config: OrientationConfig | None = None,
    *,
    extractor: OrbExtractor | None = None,
    query_bow: BowVector | None = None,
    dist_coeffs: ArrayLike | None = None,
) -> OrientationDecision:
    """Decide which of the place's M stored directions the query image faces.

    Parameters
    ----------
    query : OrbFeatures or (H, W[, 3]) image
        The image taken at the place's centre (or its features).
    place : Place
        The place with its M images in clockwise order (from :class:`VisualMap`).
    vocabulary : Vocabulary
        The vocabulary that made the stored BoW vectors.
    intrinsics : (3, 3) array or camera object
        Camera matrix, for the heading offset.
    config : OrientationConfig, optional
    extractor : OrbExtractor, optional
        Used when ``query`` is an image (default settings otherwise).
    query_bow : BowVector, optional
        Precomputed BoW vector of ``query``.
    dist_coeffs : sequence of 4 or 5 floats, optional
        OpenCV ``(k1, k2, p1, p2[, k3])`` of the camera that took the query and the stored
        images; default: ``intrinsics.dist_coeffs`` if it has them, else no distortion.
        Keypoints are undistorted before the homography (module docstring).

    Returns
    -------
    OrientationDecision
    """
    cfg = config or OrientationConfig()
    K = intrinsics_matrix(intrinsics)
    dist = dist_coeffs_of(intrinsics, dist_coeffs)
    feats = (
        query if isinstance(query, OrbFeatures) else (extractor or OrbExtractor()).extract(query)
    )
    n_kp = len(feats)
    if not place.images:
        raise ConfigurationError(f"place {place.place_id}: has no stored images")
    m = place.m
    if n_kp < cfg.min_keypoints:
        return _undecided(
            "refused",
            f"only {n_kp} keypoints (< {cfg.min_keypoints}): too little texture to decide",
            (),
            n_kp,
        )
    bow = query_bow if query_bow is not None else vocabulary.bow(feats.descriptors)
    scores = vocabulary.score_many(bow, [im.bow for im in place.images])
    order = np.argsort(-scores, kind="stable")
    best = int(order[0])
    s1 = float(scores[best])
    s2 = float(scores[order[1]]) if m > 1 else 0.0
    bow_problem = ""
    if s1 < cfg.min_score:
        bow_problem = f"best score {s1:.3f} < min_score {cfg.min_score}"
    elif m > 1 and s1 < cfg.min_score_ratio * s2:
        bow_problem = (
            f"ambiguous: best score {s1:.3f} (direction {best + 1}) is not {cfg.min_score_ratio}x "
            f"the second {s2:.3f} (direction {int(order[1]) + 1})"
        )
    if bow_problem and not cfg.geometric_fallback:
        return _undecided("undetermined", bow_problem, scores, n_kp)
    # geometric verification against every stored direction (M is small), so that a second
    # view of the same scene is caught even when the BoW ranking put it far down
    qf = undistorted(feats, K, dist)
    fits = [match_inliers(qf, undistorted(im.features, K, dist), cfg) for im in place.images]
    inliers = np.array([f[1].shape[0] for f in fits], np.int64)
    if bow_problem:
        best = int(np.argmax(inliers))
    H = fits[best][0]
    inl = int(inliers[best])
    rest = [j for j in range(m) if j != best]
    j2 = max(rest, key=lambda j: int(inliers[j])) if rest else -1
    inl2 = int(inliers[j2]) if rest else 0
    kw = {"inliers": inl, "second_inliers": inl2}
    prefix = f"{bow_problem}; by geometry: " if bow_problem else ""
    if H is None or inl < cfg.min_inliers:
        return _undecided(
            "undetermined",
            f"{prefix}geometric check failed: {inl} homography inliers for direction {best + 1} "
            f"(< {cfg.min_inliers})",
            scores,
            n_kp,
            **kw,
        )
    if inl < cfg.min_inlier_ratio * inl2:
        return _undecided(
            "undetermined",
            f"{prefix}geometric check ambiguous: {inl} inliers for direction {best + 1} against "
            f"{inl2} for direction {j2 + 1}",
            scores,
            n_kp,
            **kw,
        )
    if cfg.offset_from == "homography":
        yaw, tilt = yaw_from_homography(H, K)
    else:
        yaw, tilt, _ = rotation_from_correspondences(fits[best][1], fits[best][2], K)
    max_off = cfg.max_offset if cfg.max_offset is not None else math.pi / m
    if not math.isfinite(yaw) or abs(yaw) > max_off or tilt > cfg.max_tilt:
        return _undecided(
            "undetermined",
            f"{prefix}homography is not a small turn in place (yaw {math.degrees(yaw):.1f} deg, "
            f"tilt {math.degrees(tilt):.1f} deg)",
            scores,
            n_kp,
            **kw,
        )
    stored_heading = place.images[best].heading
    return OrientationDecision(
        status="decided",
        direction=best,
        heading_offset=yaw,
        heading=float(wrap_angle(stored_heading + yaw)),
        scores=tuple(float(x) for x in scores),
        best_score=s1,
        second_score=s2,
        inliers=inl,
        second_inliers=inl2,
        n_keypoints=n_kp,
        reason=(
            f"direction {best + 1} by geometry ({bow_problem}): {inl} inliers vs {inl2}"
            if bow_problem
            else f"direction {best + 1}: score {s1:.3f} vs {s2:.3f}, {inl} inliers vs {inl2}"
        ),
        homography=H,
    )


def decide_with_retries(
    capture: Callable[[int], OrbFeatures | ArrayLike],
    place: Place,
    vocabulary: Vocabulary,
    intrinsics: ArrayLike | object,
    config: OrientationConfig | None = None,
    *,
    extractor: OrbExtractor | None = None,
    dist_coeffs: ArrayLike | None = None,
) -> OrientationDecision:
    """The paper's protocol: try, and if undecided turn clockwise by 360/M and try again.

    Parameters
    ----------
    capture : callable
        ``capture(t)`` returns the image (or features) after the robot turned clockwise by
        ``t * 360/M`` degrees from where it started, t = 0..M-1.

    Returns
    -------
    OrientationDecision
        With ``direction`` referring to the robot's *starting* heading: an image decided as
        direction j at attempt t means the robot started facing direction ``(j - t) mod M``
        (stored images are in clockwise order); ``heading`` is the current heading after the
        t turns; ``attempts`` counts the images tried.
    """
    m = place.m
    last: OrientationDecision | None = None
    for t in range(m):
        d = decide_orientation(
            capture(t),
            place,
            vocabulary,
            intrinsics,
            config,
            extractor=extractor,
            dist_coeffs=dist_coeffs,
        )
        if d.decided and d.direction is not None:
            return OrientationDecision(
                **{
                    **d.__dict__,
                    "direction": (d.direction - t) % m,
                    "attempts": t + 1,
                    "reason": d.reason + f" (attempt {t + 1}, after {t} clockwise turns)",
                }
            )
        last = d
    assert last is not None
    return OrientationDecision(
        **{**last.__dict__, "attempts": m, "reason": f"undecided after {m} attempts: {last.reason}"}
    )
