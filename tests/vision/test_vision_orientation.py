"""The orientation decision: decided / undetermined / refused, heading offset, retries."""

from __future__ import annotations

import math

import numpy as np
import pytest
import vision_helpers as helpers
from hypothesis import given, settings
from hypothesis import strategies as st
from vision_helpers import K, rotated_view

from symloc.errors import ConfigurationError
from symloc.geometry import angle_diff
from symloc.vision.orb import OrbExtractor
from symloc.vision.orientation import (
    OrientationConfig,
    decide_orientation,
    decide_with_retries,
    intrinsics_matrix,
    yaw_from_homography,
)
from symloc.vision.place import Place, PlaceImage
from symloc.vision.vocabulary import Vocabulary


def _place(photos: list[np.ndarray], voc: Vocabulary, ext: OrbExtractor) -> Place:
    images = []
    for j, photo in enumerate(photos):
        f = ext.extract(rotated_view(photo, 0.0))
        images.append(PlaceImage(j, 0.5 - j * math.pi / 2, f, voc.bow(f.descriptors)))
    return Place(
        place_id=1,
        center=np.array([0.0, 0.0]),
        heading0=0.5,
        m=4,
        order=4,
        gv_distance=1.0,
        kind="square",
        images=tuple(images),
    )


def test_decides_each_direction_with_heading_offset() -> None:
    trained_vocabulary = helpers.trained_vocabulary()
    extractor = helpers.extractor()
    wall_photos = helpers.wall_photos()
    place = _place(wall_photos, trained_vocabulary, extractor)
    for j, yaw in enumerate([0.06, -0.04, 0.0, -0.08]):
        d = decide_orientation(rotated_view(wall_photos[j], yaw), place, trained_vocabulary, K)
        assert d.status == "decided", d.reason
        assert d.direction == j
        assert d.heading_offset == pytest.approx(yaw, abs=math.radians(0.5))
        assert angle_diff(d.heading, place.images[j].heading + yaw) == pytest.approx(0.0, abs=1e-2)
        assert d.best_score >= 2 * d.second_score
        assert d.inliers >= 20


def test_refuses_featureless_images() -> None:
    trained_vocabulary = helpers.trained_vocabulary()
    extractor = helpers.extractor()
    wall_photos = helpers.wall_photos()
    place = _place(wall_photos, trained_vocabulary, extractor)
    flat = np.full((480, 640, 3), 200, np.uint8)
    d = decide_orientation(flat, place, trained_vocabulary, K)
    assert d.status == "refused"
    assert d.direction is None
    assert math.isnan(d.heading)
    assert "keypoints" in d.reason
    # a few blobs: some keypoints, but under 100
    sparse = flat.copy()
    sparse[200:230, 300:330] = 0
    d2 = decide_orientation(sparse, place, trained_vocabulary, K)
    assert d2.status == "refused"
    assert d2.n_keypoints < 100


def test_symmetric_views_are_undetermined() -> None:
    trained_vocabulary = helpers.trained_vocabulary()
    extractor = helpers.extractor()
    wall_photos = helpers.wall_photos()
    # a room that looks the same in all four directions: never pick one
    place = _place([wall_photos[0]] * 4, trained_vocabulary, extractor)
    d = decide_orientation(rotated_view(wall_photos[0], 0.02), place, trained_vocabulary, K)
    assert d.status == "undetermined"
    assert d.direction is None
    assert "ambiguous" in d.reason


def test_unknown_view_is_undetermined() -> None:
    trained_vocabulary = helpers.trained_vocabulary()
    extractor = helpers.extractor()
    wall_photos = helpers.wall_photos()
    import skimage.data

    place = _place(wall_photos, trained_vocabulary, extractor)
    d = decide_orientation(
        rotated_view(skimage.data.hubble_deep_field(), 0.0), place, trained_vocabulary, K
    )
    assert d.status == "undetermined"


def test_retry_protocol_turns_clockwise() -> None:
    trained_vocabulary = helpers.trained_vocabulary()
    extractor = helpers.extractor()
    wall_photos = helpers.wall_photos()
    place = _place(wall_photos, trained_vocabulary, extractor)
    flat = np.full((480, 640), 128, np.uint8)
    start = 1  # the robot starts facing direction 1, but the first image is blank (occluded)

    def capture(t: int) -> np.ndarray:
        return flat if t == 0 else rotated_view(wall_photos[(start + t) % 4], 0.03)

    d = decide_with_retries(capture, place, trained_vocabulary, K)
    assert d.decided
    assert d.attempts == 2
    assert d.direction == start
    never = decide_with_retries(lambda t: flat, place, trained_vocabulary, K)
    assert never.status == "refused"
    assert never.attempts == 4


@settings(max_examples=25, deadline=None)
@given(st.floats(-0.6, 0.6))
def test_yaw_from_pure_rotation_homography(yaw: float) -> None:
    c, s = math.cos(yaw), math.sin(yaw)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    H = 3.7 * (K @ R @ np.linalg.inv(K))  # homographies are defined up to scale
    got, tilt = yaw_from_homography(H, K)
    assert got == pytest.approx(yaw, abs=1e-9)
    assert tilt == pytest.approx(0.0, abs=1e-6)


def test_config_and_intrinsics_validation() -> None:
    with pytest.raises(ConfigurationError, match="min_score_ratio"):
        OrientationConfig(min_score_ratio=1.0)
    with pytest.raises(ConfigurationError, match="lowe_ratio"):
        OrientationConfig(lowe_ratio=1.5)
    with pytest.raises(ConfigurationError, match="min_inliers"):
        OrientationConfig(min_inliers=3)
    with pytest.raises(ConfigurationError, match="min_keypoints"):
        OrientationConfig(min_keypoints=0)
    with pytest.raises(ConfigurationError, match="3x3 camera matrix"):
        intrinsics_matrix(np.eye(2))

    class Cam:
        fx, fy, cx, cy = 500.0, 500.0, 320.0, 240.0

    assert intrinsics_matrix(Cam())[0, 2] == 320.0


def test_place_without_images_is_an_error() -> None:
    trained_vocabulary = helpers.trained_vocabulary()
    empty = Place(3, np.zeros(2), heading0=0.0, m=4, order=4, gv_distance=1.0, kind="square")
    with pytest.raises(ConfigurationError, match="place 3: has no stored images"):
        decide_orientation(np.zeros((48, 64), np.uint8), empty, trained_vocabulary, K)
