"""A pose's heading measured from keyframe features placed on the map's walls: in a small
round room, half a metre from a keyframe at the centre (where planar motion trades the yaw
against a sideways direction of travel), it finds the true turn about the centre from a coarse
one degrees off, says how sure it is, and gives nothing where the views share no wall."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.geometry import turn_about, wrap_angle
from symloc.grid.fields import surface_distance_field
from symloc.sim.camera import Camera
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import build_room
from symloc.vision.bow import BowVector
from symloc.vision.keyframes import Keyframe
from symloc.vision.landmark_heading import (
    LandmarkSettings,
    column_bearings,
    landmark_heading,
    wall_points,
)
from symloc.vision.orb import OrbExtractor


@pytest.fixture(scope="module")
def room():
    """A textured round room 2.3 m in radius (dev circle#18's size), its map at 5 cm, a
    keyframe at the centre; queries 0.5 m from it, as the localizer stands after driving
    towards the centre."""
    room = build_room("circle", 2.3, lab=False, textured=True)
    cam, ex = Camera(), OrbExtractor()
    c = np.asarray(room.center, np.float64)
    walls = surface_distance_field(world_to_grid(room.world, 0.05), 1.0)
    kf_pose = np.array([c[0], c[1], 0.4])
    kf = Keyframe(
        kf_pose,
        ex.extract(cam.render(room.world, kf_pose, 1)),
        BowVector.from_dict({0: 1.0}),
        keyframe_id=7,
    )
    return room, cam, ex, c, walls, kf


def _query(room, cam, ex, c, offset, turn_deg, seed):
    truth = np.array([c[0] + offset[0], c[1] + offset[1], 0.4 + math.radians(turn_deg)])
    return truth, ex.extract(cam.render(room.world, truth, seed))


def test_wall_points_end_the_rays_on_the_round_wall(room) -> None:
    _, _, _, c, walls, _ = room
    pose = np.array([c[0] + 0.5, c[1] - 0.3, 1.0])
    pts = wall_points(pose, np.radians([-30.0, 0.0, 25.0]), walls, 20.0)
    # within half a cell (and the rasterised circle's own cell) of the 2.3 m wall
    np.testing.assert_allclose(np.hypot(*(pts - c).T), 2.3, atol=0.06)
    # a ray from outside the walls, pointing away from them, meets nothing
    out = wall_points(np.array([c[0] + 10.0, c[1], 0.0]), np.zeros(1), walls, 5.0)
    assert np.all(np.isnan(out))


def test_column_bearings_are_left_positive() -> None:
    K = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])
    b = column_bearings(np.array([[320.0, 10.0], [0.0, 0.0], [820.0, 5.0]]), K)
    np.testing.assert_allclose(b, [0.0, math.atan(320 / 500), -math.atan(500 / 500)])


@pytest.mark.parametrize(
    ("offset", "turn_deg", "start_deg"),
    [((-0.4, 0.3), 20.0, 6.0), ((0.3, -0.4), -20.0, -8.0), ((0.5, 0.0), 10.0, 4.0)],
)
def test_finds_the_turn_about_the_centre(room, offset, turn_deg, start_deg) -> None:
    rm, cam, ex, c, walls, kf = room
    truth, query = _query(rm, cam, ex, c, offset, turn_deg, 11)
    # the laser put the pose at the right distance from the centre; the camera's coarse
    # verification turned it about the centre by start_deg
    coarse = turn_about(truth, c, math.radians(start_deg))
    got = landmark_heading(coarse, query, kf, cam.calibration.K, walls, c)
    assert got is not None
    err = math.degrees(abs(float(wrap_angle(got.heading - truth[2]))))
    assert err < 0.5
    # the position followed the heading about the centre
    assert math.hypot(*(got.pose[:2] - truth[:2])) < 0.01
    assert got.inliers >= 20
    assert math.radians(0.3) <= got.std < math.radians(1.0)
    assert err < 3.0 * math.degrees(got.std)


def test_the_store_measures_a_round_rooms_heading_from_two_keyframes(room, tmp_path) -> None:
    """VisionPlaceStore.verify(refine=True) on a round map: with the map's walls two keyframes
    near the centre that agree measure the verified heading; one alone has nothing to agree
    with and gives nothing."""
    from symloc.localizer.vision_store import VisionPlaceStore
    from symloc.vision.default_vocabulary import default_vocabulary
    from symloc.vision.visual_map import VisualMap

    rm, cam, ex, c, walls, kf = room
    second = np.array([c[0] + 0.1, c[1] - 0.1, 0.4 + math.radians(15.0)])
    kfs = [kf, Keyframe(second, ex.extract(cam.render(rm.world, second, 2)), kf.bow)]
    truth = np.array([c[0] - 0.4, c[1] + 0.3, 0.4 + math.radians(20.0)])
    image = cam.render(rm.world, truth, 11)
    coarse = turn_about(truth, c, math.radians(6.0))
    voc = default_vocabulary()
    answers = {}
    for count in (2, 1):
        with VisualMap(tmp_path / f"round{count}.sqlite") as vm:
            vm.add_keyframes(
                [Keyframe(k.pose, k.features, voc.bow(k.features.descriptors)) for k in kfs[:count]]
            )
            store = VisionPlaceStore(vm, voc, cam.calibration)
            answers[count] = store.verify(
                coarse.reshape(1, 3), image, refine=True, round_centre=c, walls=walls
            )
    assert answers[2].index == 0, answers[2].reason
    err = math.degrees(abs(float(wrap_angle(answers[2].refined_heading - truth[2]))))
    assert err < 0.5
    assert math.radians(0.3) <= answers[2].heading_std < math.radians(1.0)
    assert answers[1].index == 0
    assert math.isnan(answers[1].refined_heading)


def test_views_of_other_walls_give_nothing(room) -> None:
    rm, cam, ex, c, walls, kf = room
    truth, query = _query(rm, cam, ex, c, (0.3, 0.2), 180.0, 12)
    assert landmark_heading(truth, query, kf, cam.calibration.K, walls, c) is None


def test_settings_are_checked() -> None:
    with pytest.raises(ConfigurationError, match=r"LandmarkSettings\.window"):
        LandmarkSettings(window=0.0)
    with pytest.raises(ConfigurationError, match=r"LandmarkSettings\.min_share"):
        LandmarkSettings(min_share=1.5)
    with pytest.raises(ConfigurationError, match=r"LandmarkSettings\.min_inliers"):
        LandmarkSettings(min_inliers=2)
