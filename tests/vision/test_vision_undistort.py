"""The orientation decision with a distorting lens: keypoints are undistorted before fitting."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
import vision_helpers as helpers
from vision_helpers import H, K, W, rotated_view

from symloc.camera_model import CameraModel
from symloc.vision.orientation import decide_orientation, dist_coeffs_of
from symloc.vision.place import Place, PlaceImage

# Raspberry Pi camera v2 (UbiquityRobotics/raspicam_node camerav2_1280x960.yaml) and a wide
# barrel lens
LENSES = [(0.1349735, -0.2335870, 0.0006697, 0.0048467, 0.0), (-0.3, 0.1, 0.0, 0.0, 0.0)]


def _distorter(cam: CameraModel):
    uu, vv = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    und = cam.undistort_points(np.column_stack([uu.ravel(), vv.ravel()]))
    und = und.reshape(H, W, 2).astype(np.float32)
    return lambda img: cv2.remap(img, und[:, :, 0], und[:, :, 1], cv2.INTER_LINEAR)


@pytest.mark.parametrize("dist", LENSES)
def test_undistorted_keypoints_give_the_heading_offset(dist: tuple[float, ...]) -> None:
    cam = CameraModel(W, H, K[0, 0], K[1, 1], K[0, 2], K[1, 2], dist)
    distort = _distorter(cam)
    voc = helpers.trained_vocabulary()
    ext = helpers.extractor()
    photos = helpers.wall_photos()
    images = []
    for j, photo in enumerate(photos):
        f = ext.extract(distort(rotated_view(photo, 0.0)))
        images.append(PlaceImage(j, 0.5 - j * math.pi / 2, f, voc.bow(f.descriptors)))
    place = Place(
        place_id=1,
        center=np.array([0.0, 0.0]),
        heading0=0.5,
        m=4,
        order=4,
        gv_distance=1.0,
        kind="square",
        images=tuple(images),
    )
    yaw = 0.25
    query = distort(rotated_view(photos[1], yaw))
    raw = decide_orientation(query, place, voc, K)
    fixed = decide_orientation(query, place, voc, cam)  # the calibration brings its coefficients
    explicit = decide_orientation(query, place, voc, K, dist_coeffs=dist)
    for d in (raw, fixed, explicit):
        assert d.status == "decided", d.reason
        assert d.direction == 1
    assert abs(math.degrees(fixed.heading_offset - yaw)) < 0.05
    assert explicit.heading_offset == pytest.approx(fixed.heading_offset, abs=1e-9)
    assert abs(math.degrees(raw.heading_offset - yaw)) > 0.15


def test_dist_coeffs_of() -> None:
    cam = CameraModel.from_hfov(dist_coeffs=(0.1, -0.2, 0.0, 0.0))
    assert dist_coeffs_of(cam) == (0.1, -0.2, 0.0, 0.0, 0.0)
    assert dist_coeffs_of(K) == (0.0,) * 5
    assert dist_coeffs_of(cam, (0.3, 0, 0, 0, 0))[0] == 0.3
