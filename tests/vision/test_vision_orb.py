"""ORB extraction on grey, colour, float and odd-sized images; settings validation."""

from __future__ import annotations

import numpy as np
import pytest
import skimage.data

from symloc.errors import ConfigurationError, DataFormatError
from symloc.vision.orb import OrbExtractor, OrbFeatures, OrbSettings, to_grey_uint8


def test_colour_grey_and_float_give_the_same_features() -> None:
    rgb = skimage.data.astronaut()
    ext = OrbExtractor()
    a = ext.extract(rgb)
    b = ext.extract(to_grey_uint8(rgb))
    c = ext.extract(rgb.astype(np.float64) / 255.0)
    assert len(a) == 500
    assert a.descriptors.shape == (500, 32)
    assert a.descriptors.dtype == np.uint8
    assert np.array_equal(a.descriptors, b.descriptors)
    assert len(c) == 500
    assert a.image_size == (512, 512)


def test_odd_sizes_and_settings() -> None:
    img = skimage.data.camera()[:123, :257]
    f = OrbExtractor(
        OrbSettings(n_features=100, n_levels=3, scale_factor=1.5, fast_threshold=10)
    ).extract(img)
    assert 0 < len(f) <= 100
    assert f.octaves.max() <= 2
    assert np.all(f.points[:, 0] < 257)
    kp = f.keypoint_array()
    back = OrbFeatures.from_arrays(kp, f.descriptors, f.image_size)
    assert np.array_equal(back.points, f.points)
    assert np.array_equal(back.octaves, f.octaves)


def test_featureless_image_gives_no_features() -> None:
    f = OrbExtractor().extract(np.zeros((480, 640), np.uint8))
    assert len(f) == 0
    assert f.descriptors.shape == (0, 32)


def test_errors() -> None:
    with pytest.raises(ConfigurationError, match="scale_factor"):
        OrbSettings(scale_factor=1.0)
    with pytest.raises(ConfigurationError, match="n_features"):
        OrbSettings(n_features=0)
    with pytest.raises(ConfigurationError, match="wta_k"):
        OrbSettings(wta_k=3)
    with pytest.raises(ConfigurationError, match="fast_threshold"):
        OrbSettings(fast_threshold=300)
    with pytest.raises(DataFormatError, match="expected shape"):
        to_grey_uint8(np.zeros((4, 4, 2)))
    with pytest.raises(DataFormatError, match="NaN"):
        to_grey_uint8(np.full((4, 4), np.nan))
    with pytest.raises(DataFormatError, match="mask: expected shape"):
        OrbExtractor().extract(np.zeros((8, 8), np.uint8), mask=np.ones((4, 4)))


def test_threads_setting_is_restored_and_does_not_change_features() -> None:
    import cv2

    img = cv2.resize(skimage.data.astronaut(), (640, 480))
    before = cv2.getNumThreads()
    one = OrbExtractor(OrbSettings(threads=1)).extract(img)
    assert cv2.getNumThreads() == before
    default = OrbExtractor(OrbSettings(threads=0)).extract(img)
    np.testing.assert_array_equal(one.descriptors, default.descriptors)
    np.testing.assert_array_equal(one.points, default.points)
    with pytest.raises(ConfigurationError, match="threads: expected an integer >= 0"):
        OrbSettings(threads=-1)
