"""The orientation decision on real photographs (re-captures, ambiguous and featureless places)."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.bench.photos import (
    PLACE_PHOTOS,
    VIEW_K,
    flat_wall,
    load_scene,
    make_place,
    perturb,
    run_photos,
    view,
)
from symloc.errors import ConfigurationError, DataFormatError
from symloc.vision.default_vocabulary import _sources, default_vocabulary
from symloc.vision.image_files import place_images_from_files
from symloc.vision.orb import OrbExtractor
from symloc.vision.orientation import (
    OrientationConfig,
    decide_orientation,
    rotation_from_correspondences,
)


def test_place_photos_are_not_vocabulary_training_images() -> None:
    import skimage.data

    train = [cv2.resize(s, (64, 64)).astype(np.int16) for s in _sources()]
    for name in PLACE_PHOTOS:
        grey = cv2.cvtColor(getattr(skimage.data, name)(), cv2.COLOR_RGB2GRAY)
        small = cv2.resize(grey, (64, 64)).astype(np.int16)
        assert min(np.abs(small - t).mean() for t in train) > 10


def test_view_is_a_rotation_homography() -> None:
    scene = load_scene("astronaut")
    straight = view(scene)
    assert straight.shape == (480, 640, 3)
    np.testing.assert_array_equal(straight, scene[120:600, 160:800])
    # a 4 deg left turn moves the scene right by f tan(4 deg) = 35 px at the image centre
    turned = view(scene, math.radians(4.0))
    shift = 500.0 * math.tan(math.radians(4.0))
    expected = scene[120:600, 160:800][:, 300 - round(shift) : 340 - round(shift)]
    assert np.abs(turned[:, 300:340].astype(int) - expected.astype(int)).mean() < 12


def test_perturb_conditions() -> None:
    scene = load_scene("coffee")
    rng = np.random.default_rng(0)
    img, yaw = perturb(scene, "jpeg60", rng, math.radians(5.0))
    assert img.shape == (480, 640, 3)
    assert abs(yaw) <= math.radians(5.0)
    occluded, _ = perturb(scene, "occlusion", np.random.default_rng(1), 0.0)
    diff = np.any(occluded != view(scene), axis=2)
    assert 0.2 < diff.mean() < 0.45  # 25-40 % covered
    assert len(np.unique(occluded[diff], axis=0)) == 1  # by one flat colour
    with pytest.raises(ConfigurationError, match="condition: expected one of"):
        perturb(scene, "fog", rng, 0.1)
    with pytest.raises(ConfigurationError, match="no image 'nonexistent'"):
        load_scene("nonexistent")


def test_decisions_on_real_photos(tmp_path: Path) -> None:
    from symloc.bench.photos import example_views
    from symloc.figures.vision import photos_figure

    res = run_photos(
        default_vocabulary(),
        trials_per_direction=1,
        conditions=("yaw", "jpeg60", "combined"),
        rng=0,
        progress=False,
    )
    by = {c.case: c for c in (*res.conditions, *res.ambiguity)}
    # clean and JPEG re-captures: all correct, heading offset within 1 deg of the true yaw
    for case in ("yaw", "jpeg60"):
        assert by[case].correct == by[case].trials == 4
        assert by[case].heading_error_deg_max < 1.0
    # never a wrong direction, in any case
    assert all(c.wrong == 0 for c in by.values())
    # the same photo on opposite walls: those two directions are never decided
    dup = [t for t in res.trials if t.case == "duplicate" and t.direction in (0, 2)]
    assert dup
    assert all(t.status == "undetermined" for t in dup)
    assert all("ambiguous" in t.reason for t in dup)
    # ...but the retry protocol (turn 90 deg clockwise) resolves them
    assert by["duplicate"].retry_correct == by["duplicate"].trials
    near = [t for t in res.trials if t.case == "near_duplicate" and t.direction in (0, 2)]
    assert not any(t.status == "decided" for t in near)
    flat = [t for t in res.trials if t.case == "featureless" and t.direction in (0, 2)]
    assert all(t.status == "refused" for t in flat)
    d = res.to_dict()
    assert set(d["conditions"]) == {"yaw", "jpeg60", "combined"}
    assert d["ambiguity"]["duplicate"]["wrong"] == 0
    png = photos_figure(res, tmp_path / "photos.png", example_views(rng=0)[:2])
    assert png.stat().st_size > 10_000


def test_bow_only_rule_is_undetermined_when_bow_is_ambiguous() -> None:
    voc = default_vocabulary()
    ext = OrbExtractor()
    scenes = [load_scene(n) for n in PLACE_PHOTOS]
    place = make_place(scenes, voc, ext)
    q = view(scenes[1], math.radians(-2.0))
    strict = OrientationConfig(min_score_ratio=1000.0, geometric_fallback=False)
    d = decide_orientation(q, place, voc, VIEW_K, strict, extractor=ext)
    assert d.status == "undetermined"
    assert "ambiguous" in d.reason
    d2 = decide_orientation(
        q, place, voc, VIEW_K, OrientationConfig(min_score_ratio=1000.0), extractor=ext
    )
    assert d2.status == "decided"
    assert d2.direction == 1
    assert "by geometry" in d2.reason
    assert abs(math.degrees(d2.heading_offset) + 2.0) < 0.5


def test_run_photos_errors_and_featureless_files(tmp_path: Path) -> None:
    voc = default_vocabulary()
    with pytest.raises(ConfigurationError, match="expected 4 photo names"):
        run_photos(voc, photos=("astronaut",), progress=False)
    with pytest.raises(ConfigurationError, match="trials_per_direction"):
        run_photos(voc, trials_per_direction=0, progress=False)
    with pytest.raises(ConfigurationError, match="max_yaw_deg"):
        run_photos(voc, max_yaw_deg=90.0, progress=False)
    with pytest.raises(ConfigurationError, match="unknown 'fog'"):
        run_photos(voc, conditions=("fog",), progress=False)
    path = tmp_path / "flat.png"
    cv2.imwrite(str(path), view(flat_wall(0)))
    with pytest.raises(DataFormatError, match="only 0 ORB keypoints"):
        place_images_from_files([path], voc, min_keypoints=100)
    with pytest.raises(ConfigurationError, match="at least one image file"):
        place_images_from_files([], voc)


@settings(max_examples=25, deadline=None)
@given(
    yaw=st.floats(-0.3, 0.3),
    zoom=st.floats(0.8, 1.25),
    tilt=st.floats(-0.05, 0.05),
)
def test_rotation_from_correspondences_recovers_yaw_zoom_tilt(
    yaw: float, zoom: float, tilt: float
) -> None:
    rng = np.random.default_rng(0)
    src = rng.uniform([0, 0], [640, 480], size=(60, 2))
    c, s = math.cos(yaw), math.sin(yaw)
    Ry = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    ct, st_ = math.cos(tilt), math.sin(tilt)
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, ct, -st_], [0.0, st_, ct]])
    H = VIEW_K @ Ry @ Rx @ np.diag([zoom, zoom, 1.0]) @ np.linalg.inv(VIEW_K)
    p = np.column_stack([src, np.ones(60)]) @ H.T
    dst = p[:, :2] / p[:, 2:]
    got_yaw, got_tilt, got_zoom = rotation_from_correspondences(src, dst, VIEW_K, iterations=6)
    assert got_yaw == pytest.approx(yaw, abs=2e-3)
    assert got_zoom == pytest.approx(zoom, rel=5e-3)
    assert got_tilt == pytest.approx(abs(tilt), abs=3e-3)


def test_rotation_from_correspondences_degenerate_and_config() -> None:
    assert math.isnan(rotation_from_correspondences(np.zeros((1, 2)), np.zeros((1, 2)), VIEW_K)[0])
    with pytest.raises(ConfigurationError, match="offset_from: expected 'rotation' or"):
        OrientationConfig(offset_from="affine")
