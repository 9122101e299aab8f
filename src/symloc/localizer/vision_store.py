"""The visual map (:class:`symloc.vision.VisualMap`) as the localizer's :class:`PlaceStore`
and :class:`KeyframeStore`.

G-V lookup (Algorithm 5 step 6) through :meth:`VisualMap.find_places`, the orientation decision
(step 7) through :func:`symloc.vision.orientation.decide_orientation`, and new places
(step 11) through :meth:`VisualMap.add_place` with ORB features and BoW vectors made here.
A decision whose best BoW score is below the decision's ``min_score`` is reported as
``no_match`` (the image resembles none of the place's views: a different place with the same
G-V distance, or a new one). Pose hypotheses are verified against the map's keyframes
(:meth:`VisionPlaceStore.verify`, :func:`symloc.vision.verification.verify_hypotheses`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import turn_about
from symloc.symmetry.order import SymmetryOrder
from symloc.vision.heading_refinement import RefinedHeading, RefinementSettings, refine_heading
from symloc.vision.orb import OrbFeatures
from symloc.vision.place import UNANCHORED_LABEL
from symloc.vision.verification import (
    HypothesisCheck,
    VerificationDecision,
    VerificationSettings,
    expected_counts,
    verify_hypotheses,
)

from .types import Decision, DecisionStatus, HypothesisVerdict, Place, Verification
from .verified_together import is_rival, same_view

__all__ = ["UNANCHORED_LABEL", "VisionPlaceStore", "single_verified"]

FloatArray = NDArray[np.float64]


def single_verified(
    dec: VerificationDecision, margin: float, heading_tolerance: float
) -> tuple[int | None, str]:
    """The one hypothesis ``dec`` verifies with margin, or None, and why.

    As :func:`~symloc.vision.verification.verify_hypotheses` decides (exactly one verified,
    with ``margin`` times the inliers of every rival), except for what counts as a rival. A
    hypothesis turned away from the verified one (by more than ``heading_tolerance`` [rad])
    whose best fit measures the camera's map heading as the verified one's (within the
    tolerance), on a keyframe the verified hypothesis should be seeing too, is no rival: that
    fit is evidence for the verified heading (near a symmetric room's centre every rotated copy
    sees the same keyframes, and the measurement tells them apart). Every other hypothesis with
    a fit is a rival: one with the verified heading (the camera does not measure position), one
    whose fit measures another heading, and one whose fit is on a keyframe elsewhere."""
    checks = dec.checks
    verified = [i for i, c in enumerate(checks) if c.verified]
    if len(verified) != 1:
        return None, dec.reason
    i = verified[0]
    heading = float(checks[i].corrected_pose[2])
    seen = (checks[i].expected,)
    best_rival = max(
        (
            c.inliers
            for j, c in enumerate(checks)
            if j != i
            and is_rival(
                float(c.pose[2]),
                c.heading_offset,
                heading,
                heading_tolerance,
                same_view=same_view(c.keyframe_id, seen),
            )
        ),
        default=0,
    )
    if checks[i].inliers < margin * best_rival:
        return None, (
            f"hypothesis {i + 1} verified with {checks[i].inliers} inliers, but a rival fits "
            f"with {best_rival} (margin {margin:g}x not met)"
        )
    return i, (
        f"hypothesis {i + 1} verified: {checks[i].inliers} inliers against at most "
        f"{best_rival} for a rival"
    )


class VisionPlaceStore:
    """A :class:`~symloc.localizer.types.PlaceStore` over a :class:`symloc.vision.VisualMap`.

    Parameters
    ----------
    visual_map : VisualMap
    vocabulary : Vocabulary
    intrinsics : (3, 3) array or camera object
        For the heading offset read from the homography (a
        :class:`symloc.camera_model.CameraModel` brings its distortion coefficients too).
    gv_tolerance : float
        G-V index tolerance [m]: a place matches when its G-V distance is within this.
    gv_relative_tolerance : float
        Added tolerance as a fraction of the G-V distance.
    keep_images : bool
        Store the images themselves (PNG) with the features (for figures).
    dist_coeffs : sequence of 4 or 5 floats, optional
        The camera's lens distortion ``(k1, k2, p1, p2[, k3])`` (OpenCV order); keypoints are
        undistorted before every homography. Default: ``intrinsics.dist_coeffs`` if the camera
        object has them, else none.
    """

    def __init__(
        self,
        visual_map: Any,
        vocabulary: Any,
        intrinsics: Any,
        *,
        gv_tolerance: float = 0.05,
        gv_relative_tolerance: float = 0.03,
        orientation_config: Any = None,
        extractor: Any = None,
        keep_images: bool = True,
        dist_coeffs: Any = None,
        verification: VerificationSettings | None = None,
    ) -> None:
        from symloc.vision.orb import OrbExtractor
        from symloc.vision.orientation import dist_coeffs_of

        self.visual_map = visual_map
        self.vocabulary = vocabulary
        self.intrinsics = intrinsics
        self.dist_coeffs = dist_coeffs_of(intrinsics, dist_coeffs)
        self.gv_tolerance = check_positive(gv_tolerance, "gv_tolerance")
        self.gv_relative_tolerance = check_positive(
            gv_relative_tolerance, "gv_relative_tolerance", allow_zero=True
        )
        self.orientation_config = orientation_config
        self.extractor = extractor if extractor is not None else OrbExtractor()
        self.keep_images = keep_images
        self._places: dict[int, Place] = {}
        self.last_decision: Any = None
        #: thresholds of :meth:`verify` (:class:`symloc.vision.verification.VerificationSettings`)
        self.verification = verification if verification is not None else VerificationSettings()
        #: the last :meth:`verify`'s full answer (every hypothesis' check), for notes and tests
        self.last_verification: VerificationDecision | None = None
        #: how :meth:`verify` measures a verified heading again
        #: (:class:`symloc.vision.heading_refinement.RefinementSettings`)
        self.refinement = RefinementSettings()
        self._kf_poses: FloatArray | None = None

    def _vplace(self, place_id: int) -> Place:
        if place_id not in self._places:
            self._places[place_id] = self.visual_map.place(place_id)
        return self._places[place_id]

    def all_places(self) -> list[Place]:
        """Every stored place (the localizer's ``known_places``)."""
        return [self._vplace(i) for i in self.visual_map.place_ids()]

    def candidates(self, gv_distance: float, order: SymmetryOrder) -> list[Place]:
        if not math.isfinite(gv_distance):
            return []
        tol = self.gv_tolerance + self.gv_relative_tolerance * abs(gv_distance)
        rows = self.visual_map.find_places(gv_distance, tol)
        return [self._vplace(pid) for pid, _gv in rows]

    def decide(self, place: Place, image: NDArray[np.uint8]) -> Decision:
        from symloc.vision.orientation import OrientationConfig, decide_orientation

        cfg = self.orientation_config or OrientationConfig()
        d = decide_orientation(
            image,
            self._vplace(place.place_id),
            self.vocabulary,
            self.intrinsics,
            cfg,
            extractor=self.extractor,
            dist_coeffs=self.dist_coeffs,
        )
        self.last_decision = d
        status = DecisionStatus(d.status)
        if (
            status is DecisionStatus.UNDETERMINED
            and math.isfinite(d.best_score)
            and d.best_score < cfg.min_score
        ):
            status = DecisionStatus.NO_MATCH
        return Decision(
            status=status,
            direction=d.direction,
            offset=0.0 if not math.isfinite(d.heading_offset) else float(d.heading_offset),
            score=0.0 if not math.isfinite(d.best_score) else float(d.best_score),
            reason=d.reason,
            heading=float(d.heading) if status is DecisionStatus.DECIDED else None,
        )

    # ------------------------------------------------------------------ keyframes

    def keyframe_count(self) -> int:
        """Keyframes in the visual map (:class:`~symloc.localizer.types.KeyframeStore`)."""
        return int(self.visual_map.keyframe_count())

    def expected_counts(self, poses: FloatArray, reach: float = 0.0) -> NDArray[np.int64]:
        """Keyframes each pose of ``poses`` (P, 3) should see, (P,)
        (:func:`symloc.vision.verification.expected_counts` with :attr:`verification`, its
        ``max_distance`` lengthened by ``reach`` [m])."""
        return expected_counts(poses, self._keyframe_poses(), self._reaching(reach))

    def _reaching(self, reach: float) -> VerificationSettings:
        """:attr:`verification` with expected keyframes up to ``reach`` [m] further away."""
        if not (math.isfinite(reach) and reach >= 0.0):
            raise ConfigurationError(f"reach: expected a distance >= 0 m, got {reach!r}")
        if reach == 0.0:
            return self.verification
        cfg = self.verification
        return replace(cfg, max_distance=cfg.max_distance + reach)

    def _keyframe_poses(self) -> FloatArray:
        """The keyframes' map poses (N, 3), read once per keyframe count."""
        n = self.keyframe_count()
        if self._kf_poses is None or self._kf_poses.shape[0] != n:
            self._kf_poses = np.asarray(self.visual_map.keyframe_poses()[1], np.float64).reshape(
                -1, 3
            )
        return self._kf_poses

    def verify(
        self,
        poses: FloatArray,
        image: NDArray[np.uint8],
        reach: float = 0.0,
        *,
        refine: bool = False,
        round_centre: FloatArray | None = None,
    ) -> Verification:
        """:func:`symloc.vision.verification.verify_hypotheses` of ``poses`` (K, 3) against
        ``image`` with this store's vocabulary, camera and :attr:`verification` settings (the
        expected keyframes up to ``reach`` [m] further away); with ``refine`` the verified
        hypothesis' heading measured again (:meth:`refine`), on a round map about its
        ``round_centre`` (2,) [m]."""
        query = self.extractor.extract(image)
        dec = verify_hypotheses(
            np.asarray(poses, dtype=np.float64).reshape(-1, 3),
            query,
            self.visual_map,
            self.vocabulary,
            self.intrinsics,
            self._reaching(reach),
            extractor=self.extractor,
            dist_coeffs=self.dist_coeffs,
        )
        self.last_verification = dec
        cfg = self.verification
        index, reason = single_verified(dec, cfg.margin, cfg.heading_tolerance)
        pose = None if index is None else dec.checks[index].corrected_pose
        refined = (
            None
            if not refine or pose is None or index is None
            else self.refine(pose, query, dec.checks[index], round_centre)
        )
        checks = tuple(
            HypothesisVerdict(c.status, c.inliers, c.heading_offset, c.keyframe_id, c.expected)
            for c in dec.checks
        )
        return Verification(
            index,
            pose,
            reason,
            dict(dec.counts),
            checks=checks,
            margin=cfg.margin,
            heading_tolerance=cfg.heading_tolerance,
            refined_heading=math.nan if refined is None else refined.heading,
            heading_std=math.nan if refined is None else refined.std,
        )

    def refine(
        self,
        pose: FloatArray,
        query: OrbFeatures,
        check: HypothesisCheck,
        round_centre: FloatArray | None = None,
    ) -> RefinedHeading | None:
        """The heading of a verified ``pose`` (3,) measured again by planar motion
        (:func:`symloc.vision.heading_refinement.refine_heading`) against the keyframes
        ``check`` expected, the one that verified it first (None: no fit counts, or they
        disagree). On a round map (``round_centre`` (2,) [m]) the pose is first turned about
        the centre to the check's heading, and its position follows the heading there."""
        if round_centre is not None:
            pose = turn_about(check.pose, round_centre, check.heading_offset)
        ids = list(check.expected)
        if check.keyframe_id is not None:
            ids = [check.keyframe_id] + [i for i in ids if i != check.keyframe_id]
        cfg = self.refinement
        kfs = [self.visual_map.keyframe(i) for i in ids[: cfg.max_keyframes]]
        return refine_heading(
            pose,
            query,
            kfs,
            self.intrinsics,
            cfg,
            dist_coeffs=self.dist_coeffs,
            centre=round_centre,
        )

    def stored_image(self, place_id: int, direction: int) -> NDArray[np.uint8] | None:
        """The stored image of one direction (None if images were not kept)."""
        vp = self._vplace(place_id)
        img = vp.images[direction].image
        return None if img is None else np.asarray(img)

    def add_place(
        self,
        center: FloatArray,
        heading0: float,
        order: SymmetryOrder,
        gv_distance: float,
        kind: str,
        images: Sequence[NDArray[np.uint8]],
        headings: Sequence[float] | None = None,
        *,
        label: str | None = None,
    ) -> Place:
        from symloc.vision.visual_map import PlaceImage, direction_headings

        m = len(images)
        heads = (
            direction_headings(float(heading0), m)
            if headings is None
            else np.asarray(headings, dtype=np.float64)
        )
        stored = []
        for j, image in enumerate(images):
            feats = self.extractor.extract(image)
            bow = self.vocabulary.bow(feats.descriptors)
            stored.append(
                PlaceImage(
                    direction=j,
                    heading=float(heads[j]),
                    features=feats,
                    bow=bow,
                    image=np.asarray(image) if self.keep_images else None,
                )
            )
        pid = self.visual_map.add_place(
            kind=kind,
            order=order,
            gv_distance=float(gv_distance),
            pose=np.array([center[0], center[1], heading0], dtype=np.float64),
            images=stored,
            label=label,
        )
        self._places.pop(pid, None)
        return self._vplace(pid)
