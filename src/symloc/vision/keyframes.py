"""Keyframes: views recorded all along the mapping trip, each with its map pose.

A keyframe is one camera image of the mapping trip reduced to what verification needs: the map
pose of the robot when it was taken (from SLAM), its ORB keypoints and descriptors, and its BoW
vector (optionally the image itself). :class:`~symloc.vision.visual_map.VisualMap` stores them in
its ``keyframes`` table; :mod:`symloc.vision.verification` asks them whether a pose hypothesis
explains a query image.

:class:`KeyframeSelector` decides which frames of the trip become keyframes (the rule of
:class:`KeyframeSettings`): a frame is kept when the camera moved more than ``min_translation``
or turned more than ``min_rotation`` since the last keyframe, or when the part of the last
keyframe's features it still sees (its covisibility) dropped below ``min_covisibility``. The
defaults keep consecutive keyframes overlapping: a 20 degree turn leaves about two thirds of a
65 degree field of view in common, and 0.5 m of travel at 1.5-3 m from the walls keeps most of
the view.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError
from symloc.geometry import angle_diff
from symloc.vision.bow import BowVector
from symloc.vision.orb import OrbExtractor, OrbFeatures
from symloc.vision.two_view import ratio_matches

__all__ = [
    "Keyframe",
    "KeyframeDecision",
    "KeyframeRecorder",
    "KeyframeSelector",
    "KeyframeSettings",
]

FloatArray = NDArray[np.float64]


def _pose3(pose: ArrayLike, name: str) -> FloatArray:
    p = np.asarray(pose, np.float64).reshape(-1)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ConfigurationError(f"{name}: expected 3 finite values (x, y, theta), got {pose!r}")
    return p


@dataclass(frozen=True, eq=False)
class Keyframe:
    """One stored view of the mapping trip.

    Attributes
    ----------
    pose : (3,) float64
        Map pose of the robot (x [m], y [m], theta [rad]) when the image was taken; the camera
        looks along theta (it sits on the robot's base, its axis along the laser's +x).
    features : OrbFeatures
        ORB keypoints (pixel positions as the camera gave them) and descriptors.
    bow : BowVector
        The BoW vector of the descriptors (the visual map's vocabulary).
    stamp : float
        Time [s] on the mapping trip (0 if unknown).
    keyframe_id : int
        Id in the visual map (-1 before it is stored).
    image : (H, W[, 3]) uint8 or None
        The image, only when asked to keep it (it dominates the storage).
    """

    pose: FloatArray
    features: OrbFeatures
    bow: BowVector
    stamp: float = 0.0
    keyframe_id: int = -1
    image: NDArray[np.uint8] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "pose", _pose3(self.pose, "Keyframe.pose"))
        if not math.isfinite(float(self.stamp)):
            raise ConfigurationError(f"Keyframe.stamp: expected a finite time, got {self.stamp}")


@dataclass(frozen=True)
class KeyframeSettings:
    """The keyframe selection rule (see the module docstring).

    Attributes
    ----------
    min_translation : float
        A new keyframe once the camera moved more than this [m] since the last one, > 0.
    min_rotation : float
        ... or turned more than this [rad] since the last one, in (0, pi].
    min_covisibility : float
        ... or when the fraction of the last keyframe's features matched in the current frame
        fell below this, in [0, 1) (0 disables the test).
    min_features : int
        Frames with fewer ORB features are not kept (an untextured view verifies nothing).
    lowe_ratio : float
        Lowe's ratio of the covisibility matching, in (0, 1).
    """

    min_translation: float = 0.5
    min_rotation: float = math.radians(20.0)
    min_covisibility: float = 0.25
    min_features: int = 50
    lowe_ratio: float = 0.8

    def __post_init__(self) -> None:
        if not (math.isfinite(self.min_translation) and self.min_translation > 0):
            raise ConfigurationError(
                f"KeyframeSettings.min_translation: expected a distance > 0 m, got "
                f"{self.min_translation}"
            )
        if not (math.isfinite(self.min_rotation) and 0 < self.min_rotation <= math.pi):
            raise ConfigurationError(
                f"KeyframeSettings.min_rotation: expected an angle in (0, pi] rad, got "
                f"{self.min_rotation}"
            )
        if not (math.isfinite(self.min_covisibility) and 0 <= self.min_covisibility < 1):
            raise ConfigurationError(
                f"KeyframeSettings.min_covisibility: expected a fraction in [0, 1), got "
                f"{self.min_covisibility}"
            )
        if (
            isinstance(self.min_features, bool)
            or int(self.min_features) != self.min_features
            or self.min_features < 0
        ):
            raise ConfigurationError(
                f"KeyframeSettings.min_features: expected an integer >= 0, got {self.min_features}"
            )
        if not 0.0 < self.lowe_ratio < 1.0:
            raise ConfigurationError(
                f"KeyframeSettings.lowe_ratio: expected a value in (0, 1), got {self.lowe_ratio}"
            )


@dataclass(frozen=True)
class KeyframeDecision:
    """Whether a frame becomes a keyframe, and why (``reason`` in words)."""

    keep: bool
    reason: str
    moved: float = math.nan
    turned: float = math.nan
    covisibility: float = math.nan


class KeyframeSelector:
    """Applies :class:`KeyframeSettings` to the frames of a trip, in order.

    :meth:`pose_due` is the cheap test (pose only): a caller that renders or grabs images on
    demand asks it first. :meth:`consider` gives the full decision for a frame (its features
    add the covisibility test) and :meth:`accept` records a kept keyframe as the new reference.
    """

    def __init__(self, settings: KeyframeSettings | None = None) -> None:
        self.settings = settings if settings is not None else KeyframeSettings()
        self._last_pose: FloatArray | None = None
        self._last_features: OrbFeatures | None = None

    @property
    def last_pose(self) -> FloatArray | None:
        """Pose of the last accepted keyframe (None before the first)."""
        return None if self._last_pose is None else self._last_pose.copy()

    def _motion(self, pose: FloatArray) -> tuple[float, float]:
        assert self._last_pose is not None
        moved = float(np.hypot(*(pose[:2] - self._last_pose[:2])))
        turned = abs(float(angle_diff(pose[2], self._last_pose[2])))
        return moved, turned

    def pose_due(self, pose: ArrayLike) -> bool:
        """True when the pose alone calls for a keyframe (first frame, moved or turned)."""
        if self._last_pose is None:
            return True
        moved, turned = self._motion(_pose3(pose, "pose"))
        s = self.settings
        return moved > s.min_translation or turned > s.min_rotation

    def consider(self, pose: ArrayLike, features: OrbFeatures | None = None) -> KeyframeDecision:
        """Should the frame at ``pose`` (map frame) with ``features`` become a keyframe?

        Without ``features`` only the pose tests run (and ``min_features`` is not checked).
        """
        p = _pose3(pose, "pose")
        s = self.settings
        if features is not None and len(features) < s.min_features:
            return KeyframeDecision(
                False, f"only {len(features)} ORB features (< {s.min_features}): too little texture"
            )
        if self._last_pose is None:
            return KeyframeDecision(True, "first keyframe")
        moved, turned = self._motion(p)
        if moved > s.min_translation:
            return KeyframeDecision(
                True, f"moved {moved:.2f} m > {s.min_translation:g} m", moved, turned
            )
        if turned > s.min_rotation:
            return KeyframeDecision(
                True,
                f"turned {math.degrees(turned):.1f} deg > {math.degrees(s.min_rotation):g} deg",
                moved,
                turned,
            )
        if features is not None and s.min_covisibility > 0 and self._last_features is not None:
            n_last = len(self._last_features)
            src, _ = ratio_matches(features, self._last_features, s.lowe_ratio)
            covis = src.shape[0] / n_last if n_last else 0.0
            if covis < s.min_covisibility:
                return KeyframeDecision(
                    True,
                    f"covisibility {covis:.2f} < {s.min_covisibility:g}",
                    moved,
                    turned,
                    covis,
                )
            return KeyframeDecision(False, "close to the last keyframe", moved, turned, covis)
        return KeyframeDecision(False, "close to the last keyframe", moved, turned)

    def accept(self, pose: ArrayLike, features: OrbFeatures | None = None) -> None:
        """Make the frame at ``pose`` the reference of the next decisions."""
        self._last_pose = _pose3(pose, "pose")
        self._last_features = features


class KeyframeRecorder:
    """Keyframes all along the mapping trip (not only at symmetric places).

    :meth:`frame` is called at every frame of the trip (each scan of a simulated trip, each
    camera image of a recording) with its index, the odometry pose and what ``capture`` turns
    into the image (the robot's true pose for a simulator's renderer, the image itself for a
    recording). The selection rule (:class:`KeyframeSelector`) runs on the odometry pose (what
    the robot knows while it drives); an image is captured (and its ORB features extracted)
    only when the pose rule fires, or every ``check_every`` frames for the covisibility test.
    Kept frames wait for their map pose: :meth:`keyframes` gives them the map pose of their
    frame (SLAM's, after the trip; or any pose source).
    """

    def __init__(
        self,
        capture: Callable[[Any], NDArray[np.uint8]],
        extractor: OrbExtractor,
        settings: KeyframeSettings | None = None,
        *,
        check_every: int = 5,
    ) -> None:
        self.capture = capture
        self.extractor = extractor
        self.selector = KeyframeSelector(settings)
        self.check_every = max(1, int(check_every))
        self.frames: list[tuple[int, float, OrbFeatures]] = []
        self.captured = 0

    def frame(self, index: int, odom_pose: FloatArray, view: Any, stamp: float) -> None:
        """Consider frame ``index`` (a scan's, or an image's) at ``odom_pose`` (3,); its image
        is ``capture(view)``, taken only when the rule may keep it (a simulator renders the
        image at the true pose ``view``; a recording passes the image itself)."""
        due = self.selector.pose_due(odom_pose)
        if not due and index % self.check_every:
            return
        feats = self.extractor.extract(self.capture(view))
        self.captured += 1
        if self.selector.consider(odom_pose, feats).keep:
            self.selector.accept(odom_pose, feats)
            self.frames.append((int(index), float(stamp), feats))

    @property
    def indices(self) -> list[int]:
        """Scan index of each kept frame, in order (the bench looks up its true pose)."""
        return [i for i, _, _ in self.frames]

    def keyframes(
        self, map_pose: Callable[[int], FloatArray], bow: Callable[[OrbFeatures], BowVector]
    ) -> list[Keyframe]:
        """The kept frames as keyframes, with ``map_pose(scan_index)`` and their BoW vectors."""
        return [
            Keyframe(np.asarray(map_pose(i), np.float64), f, bow(f), stamp=t)
            for i, t, f in self.frames
        ]
