"""A verified heading measured again by planar motion: from a coarse heading degrees off it
finds the true one within a fraction of a degree, says how sure it is, and refuses views that
do not fix it or disagree."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.geometry import wrap_angle
from symloc.sim.camera import Camera
from symloc.sim.rooms import build_room
from symloc.vision.bow import BowVector
from symloc.vision.heading_refinement import RefinementSettings, refine_heading
from symloc.vision.keyframes import Keyframe
from symloc.vision.orb import OrbExtractor


@pytest.fixture(scope="module")
def views():
    """A textured round room; keyframes near its wall and a query pose beside them."""
    room = build_room("circle", 2.0, lab=False, textured=True)
    cam, ex = Camera(), OrbExtractor()
    c = np.asarray(room.center, np.float64)
    kfs = []
    for i, (dx, dy, th) in enumerate(((0.0, -0.1, 0.3), (0.15, 0.05, 0.35), (-0.1, 0.2, 0.25))):
        pose = np.array([c[0] + dx, c[1] - 0.4 + dy, th])
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
    # within a degree wherever the coarse heading started (this view's three fits share an
    # error of -0.4 to -1.5 deg: the floor is what keeps the std honest)
    assert err < 1.0
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


def test_bad_settings_name_the_field() -> None:
    with pytest.raises(ConfigurationError, match=r"RefinementSettings\.window"):
        RefinementSettings(window=2.0)
    with pytest.raises(ConfigurationError, match=r"RefinementSettings\.min_inliers"):
        RefinementSettings(min_inliers=3)
    with pytest.raises(ConfigurationError, match="pose"):
        refine_heading([0.0, 1.0], None, [], np.eye(3))  # type: ignore[arg-type]
