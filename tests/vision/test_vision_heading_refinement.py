"""A verified heading measured again by planar motion: from a coarse heading degrees off it
finds the true one within a fraction of a degree, says how sure it is, and refuses views that
do not fix it or disagree."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.geometry import turn_about, wrap_angle
from symloc.sim.camera import Camera
from symloc.sim.rooms import build_room
from symloc.vision.bow import BowVector
from symloc.vision.heading_refinement import RefinementSettings, refine_heading
from symloc.vision.keyframes import Keyframe
from symloc.vision.orb import OrbExtractor


@pytest.fixture(scope="module")
def views():
    """A textured round room; keyframes a few centimetres from a query pose, turned 2-4 deg
    from it (sideways travel, where a single fit can be 1.5 deg off, is measured in the
    module docstring, not here)."""
    room = build_room("circle", 2.0, lab=False, textured=True)
    cam, ex = Camera(), OrbExtractor()
    c = np.asarray(room.center, np.float64)
    kfs = []
    for i, (dx, dy, th) in enumerate(((0.1, -0.43, 0.28), (0.13, -0.4, 0.38), (0.08, -0.38, 0.25))):
        pose = np.array([c[0] + dx, c[1] + dy, th])
        feats = ex.extract(cam.render(room.world, pose, i))
        kfs.append(Keyframe(pose, feats, BowVector.from_dict({i: 1.0}), keyframe_id=i))
    truth = np.array([c[0] + 0.1, c[1] - 0.4, 0.32])
    query = ex.extract(cam.render(room.world, truth, 99))
    return kfs, truth, query, cam.calibration


@pytest.mark.parametrize("off_deg", [0.0, 6.0, -9.0])
def test_finds_the_true_heading_from_a_coarse_one(views, off_deg: float) -> None:
    kfs, truth, query, calib = views
    coarse = truth.copy()
    coarse[2] += math.radians(off_deg)
    got = refine_heading(coarse, query, kfs, calib)
    assert got is not None
    err = abs(math.degrees(float(wrap_angle(got.heading - truth[2]))))
    # within half a degree wherever the coarse heading started
    assert err < 0.5
    assert math.radians(0.5) <= got.std < math.radians(1.2)
    assert err < 2.0 * math.degrees(got.std)
    assert len(got.keyframes) >= 2


def test_views_that_fix_nothing_give_none(views) -> None:
    kfs, truth, query, calib = views
    # keyframes turned half a turn away see other walls: no fit counts
    away = [Keyframe(k.pose + np.array([0.0, 0.0, math.pi]), k.features, k.bow) for k in kfs]
    assert refine_heading(truth, query, away[:1], calib, RefinementSettings(window=0.1)) is None


def test_disagreeing_views_give_none(views) -> None:
    kfs, truth, query, calib = views
    # one keyframe's stored heading 3 deg off: its fit disagrees with the other's
    turned = kfs[1].pose + np.array([0.0, 0.0, math.radians(3.0)])
    bent = [kfs[0], Keyframe(turned, kfs[1].features, kfs[1].bow, keyframe_id=1)]
    assert refine_heading(truth, query, bent, calib) is None
    # one fit alone has nothing to agree with
    assert refine_heading(truth, query, kfs[:1], calib) is None
    assert refine_heading(truth, query, kfs[:1], calib, RefinementSettings(min_fits=1)) is not None


def test_two_of_three_that_agree_outvote_one_that_does_not(views) -> None:
    kfs, truth, query, calib = views
    turned = kfs[1].pose + np.array([0.0, 0.0, math.radians(3.0)])
    bent = [kfs[0], Keyframe(turned, kfs[1].features, kfs[1].bow, keyframe_id=1), kfs[2]]
    got = refine_heading(truth, query, bent, calib)
    assert got is not None
    assert set(got.keyframes) == {0, 2}
    assert abs(math.degrees(float(wrap_angle(got.heading - truth[2])))) < 0.5
    # two groups of two that each agree (0-1 and 1-2, not 0-2): no majority, nothing
    both = [
        Keyframe(
            kfs[0].pose - np.array([0.0, 0.0, math.radians(0.5)]),
            kfs[0].features,
            kfs[0].bow,
            keyframe_id=0,
        ),
        kfs[1],
        Keyframe(
            kfs[2].pose + np.array([0.0, 0.0, math.radians(0.5)]),
            kfs[2].features,
            kfs[2].bow,
            keyframe_id=2,
        ),
    ]
    assert (
        refine_heading(truth, query, both, calib, RefinementSettings(agreement=math.radians(0.3)))
        is None
    )


@pytest.mark.parametrize("off_deg", [5.0, -8.0])
def test_on_a_round_map_the_position_follows_the_heading(off_deg: float) -> None:
    """2.5 m from a round room's centre a coarse heading 5-8 deg off puts the position 22-35
    cm along the wall too, and the fits made from there are 0.9-1.3 deg off or disagree;
    with the centre they are made again from where their heading puts the pose."""
    room = build_room("circle", 4.0, lab=False, textured=True)
    cam, ex = Camera(), OrbExtractor()
    c = np.asarray(room.center, np.float64)
    kfs = []
    for i, (dx, dy, th) in enumerate(((0.1, -2.43, 0.28), (0.3, -2.4, 0.38), (-0.12, -2.38, 0.25))):
        pose = np.array([c[0] + dx, c[1] + dy, th])
        feats = ex.extract(cam.render(room.world, pose, i))
        kfs.append(Keyframe(pose, feats, BowVector.from_dict({i: 1.0}), keyframe_id=i))
    truth = np.array([c[0] + 0.1, c[1] - 2.5, 0.32])
    query = ex.extract(cam.render(room.world, truth, 99))
    coarse = turn_about(truth, c, math.radians(off_deg))
    got = refine_heading(coarse, query, kfs, cam.calibration, centre=c)
    assert got is not None
    assert abs(math.degrees(float(wrap_angle(got.heading - truth[2])))) < 0.6
    alone = refine_heading(coarse, query, kfs, cam.calibration)
    assert alone is None or abs(math.degrees(float(wrap_angle(alone.heading - truth[2])))) > 0.8
    with pytest.raises(ConfigurationError, match="centre"):
        refine_heading(truth, query, kfs, cam.calibration, centre=[0.0, math.nan])


def test_bad_settings_name_the_field() -> None:
    with pytest.raises(ConfigurationError, match=r"RefinementSettings\.window"):
        RefinementSettings(window=2.0)
    with pytest.raises(ConfigurationError, match=r"RefinementSettings\.min_inliers"):
        RefinementSettings(min_inliers=3)
    with pytest.raises(ConfigurationError, match=r"RefinementSettings\.round_attempts"):
        RefinementSettings(round_attempts=0)
    with pytest.raises(ConfigurationError, match="pose"):
        refine_heading([0.0, 1.0], None, [], np.eye(3))  # type: ignore[arg-type]


def test_the_store_measures_a_verified_heading_again(views, tmp_path) -> None:
    """VisionPlaceStore.verify names the verified hypothesis with the coarse heading and, when
    asked, adds the heading measured again and its std; with one keyframe there is nothing to
    agree."""
    from symloc.localizer.vision_store import VisionPlaceStore
    from symloc.sim.rooms import build_room as _room
    from symloc.vision.default_vocabulary import default_vocabulary
    from symloc.vision.visual_map import VisualMap

    kfs, truth, _, calib = views
    room = _room("circle", 2.0, lab=False, textured=True)
    image = Camera().render(room.world, truth, 99)
    voc = default_vocabulary()
    coarse = truth + np.array([0.0, 0.0, math.radians(5.0)])
    elsewhere = truth + np.array([0.0, 0.0, math.pi])
    for count, measured in ((3, True), (1, False)):
        with VisualMap(tmp_path / f"map{count}.sqlite") as vm:
            vm.add_keyframes(
                [Keyframe(k.pose, k.features, voc.bow(k.features.descriptors)) for k in kfs[:count]]
            )
            store = VisionPlaceStore(vm, voc, calib)
            # measured again only when asked (about a second of CPU)
            plain = store.verify(np.stack([coarse, elsewhere]), image)
            assert plain.index == 0
            assert math.isnan(plain.heading_std)
            answer = store.verify(np.stack([coarse, elsewhere]), image, refine=True)
        assert answer.index == 0, answer.reason
        assert answer.pose is not None
        assert answer.pose[2] != pytest.approx(truth[2], abs=math.radians(0.1))  # coarse
        if measured:
            err = math.degrees(abs(float(wrap_angle(answer.refined_heading - truth[2]))))
            assert err < 1.0
            assert math.radians(0.5) <= answer.heading_std < math.radians(1.2)
        else:
            assert math.isnan(answer.refined_heading)
            assert math.isnan(answer.heading_std)
