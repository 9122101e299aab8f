"""Two-view geometry shared by the orientation decision and the keyframe verification.

ORB descriptors are matched with Lowe's ratio test (:func:`ratio_matches`), keypoint positions
are undistorted when the camera has lens distortion (:func:`undistorted`), and the relative
rotation between two views is read as a yaw (a turn of a level camera about the vertical axis)
and a tilt (whatever rotation is left).

Camera frame: x right, y down, z forward (OpenCV). ``R`` maps rays of the *stored* view to rays
of the *query* view (``x_query ~ R x_stored + t``); its yaw ``atan2(R[0, 2], R[2, 2])`` is the
query heading minus the stored heading, counter-clockwise (robot turning left) positive.
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.camera_model import undistort_points
from symloc.vision.orb import OrbFeatures

__all__ = ["ratio_matches", "undistorted", "yaw_and_tilt", "yaw_rotation"]


def undistorted(
    features: OrbFeatures, K: NDArray[np.float64], dist: tuple[float, ...]
) -> OrbFeatures:
    """``features`` with undistorted keypoint positions (itself when there is no distortion)."""
    if not any(dist) or len(features) == 0:
        return features
    pts = undistort_points(features.points, K, dist).astype(np.float32)
    return replace(features, points=np.ascontiguousarray(pts))


def ratio_matches(
    query: OrbFeatures, stored: OrbFeatures, lowe_ratio: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """ORB matches ``stored -> query`` that pass Lowe's ratio test (Hamming distance).

    Returns
    -------
    src, dst : (n, 2) float64
        Stored and query pixel positions of the n matches (empty when either side has fewer
        than two keypoints).
    """
    none = np.zeros((0, 2))
    if len(query) < 2 or len(stored) < 2:
        return none, none.copy()
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING)
    knn = matcher.knnMatch(stored.descriptors, query.descriptors, k=2)
    good = [m[0] for m in knn if len(m) == 2 and m[0].distance < lowe_ratio * m[1].distance]
    if not good:
        return none, none.copy()
    src = stored.points[[m.queryIdx for m in good]].astype(np.float64)
    dst = query.points[[m.trainIdx for m in good]].astype(np.float64)
    return src, dst


def yaw_rotation(yaw: float) -> NDArray[np.float64]:
    """The camera-frame rotation ``(3, 3)`` of a turn by ``yaw`` [rad] (CCW positive) about the
    vertical axis, in the convention of :func:`yaw_and_tilt`."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def yaw_and_tilt(R: ArrayLike) -> tuple[float, float]:
    """Yaw [rad] of a camera-frame rotation ``R`` and the angle [rad] of what is left of it
    (roll and pitch; ~0 for a robot on a flat floor)."""
    Rm = np.asarray(R, np.float64)
    yaw = math.atan2(Rm[0, 2], Rm[2, 2])
    resid = yaw_rotation(yaw).T @ Rm
    tilt = math.acos(max(-1.0, min(1.0, (np.trace(resid) - 1.0) / 2.0)))
    return yaw, tilt
