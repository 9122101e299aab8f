"""The camera as a real one: texture pool, people, glass, light, blur, distortion, vignetting."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.sim.camera import Camera, CameraConditions
from symloc.sim.poster import POSTER_KINDS, poster_kind, procedural_texture
from symloc.sim.rooms import build_room
from symloc.sim.textures import (
    PHOTO_NAMES,
    TEXTURE_POOL_SIZE,
    load_photo,
    material_texture,
    person_texture,
    pool_texture,
)
from symloc.sim.world import (
    MATERIAL_DARK,
    MATERIAL_GLASS,
    MATERIAL_PERSON,
    MATERIAL_PHOTO,
    MATERIAL_WALL,
    World,
    polygon_walls,
)

RPI_V2 = (0.1349735, -0.2335870, 0.0006697, 0.0048467, 0.0)


@pytest.fixture(scope="module")
def paper_room():
    return build_room("square", 1.5 * math.sqrt(2))


def test_first_sixteen_textures_are_the_photos_and_the_pool_wraps() -> None:
    for k in (0, 5, 15):
        assert np.array_equal(material_texture(MATERIAL_PHOTO + k, 32), load_photo(k, 32))
    assert len(PHOTO_NAMES) == 16
    assert np.array_equal(pool_texture(TEXTURE_POOL_SIZE + 20, 32), pool_texture(20, 32))
    assert TEXTURE_POOL_SIZE >= 4000


def test_pool_textures_are_deterministic_and_distinct() -> None:
    ks = list(range(16, 16 + 160))
    imgs = np.array([pool_texture(k, 48) for k in ks]).astype(np.float32)
    again = procedural_texture(ks[7], 48, load_photo)
    assert np.array_equal(again, imgs[7])
    assert {poster_kind(k) for k in ks} == set(POSTER_KINDS)
    small = imgs.reshape(len(ks), 12, 4, 12, 4, 3).mean(axis=(2, 4)).reshape(len(ks), -1)
    d = np.abs(small[:, None, :] - small[None, :, :]).mean(axis=2)
    np.fill_diagonal(d, np.inf)
    assert d.min() > 5.0  # no two of 160 textures look alike (mean grey-level difference)
    far = [pool_texture(k, 48) for k in (1000, 2000, 4095)]
    assert len({f.tobytes() for f in far}) == 3


def test_pool_textures_have_features(paper_room) -> None:
    import cv2

    orb = cv2.ORB_create(500)
    counts = [
        len(orb.detect(cv2.cvtColor(np.asarray(pool_texture(k)), cv2.COLOR_RGB2GRAY), None))
        for k in range(16, 40)
    ]
    assert np.median(counts) >= 300, counts


def test_plain_dark_and_person_materials() -> None:
    dark = material_texture(MATERIAL_DARK, 16).astype(float)
    assert dark.mean() < 50
    p = person_texture(100)
    assert p.shape == (100, 100, 3)
    assert not np.array_equal(p[30, :20], p[30, 40:60])  # different clothes around a person
    assert np.array_equal(material_texture(MATERIAL_PERSON, 100), p)
    with pytest.raises(ConfigurationError, match="unknown material id 7"):
        material_texture(7, 16)


def test_glass_is_transparent_and_people_occlude_walls() -> None:
    wall = World(walls=[[2.0, -5.0, 2.0, 5.0]], wall_materials=MATERIAL_PHOTO + 3)
    glass = World(walls=[[1.0, -5.0, 1.0, 5.0]], wall_materials=MATERIAL_GLASS)
    cam = Camera(width=160, height=120, noise_sigma=0.0)
    behind = cam.render(wall, [0, 0, 0])
    assert np.array_equal(cam.render(wall + glass, [0, 0, 0]), behind)
    person = World(circles=[[1.0, 0.0, 0.25]], circle_materials=MATERIAL_PERSON, circle_heights=1.7)
    seen = cam.render(wall + person, [0, 0, 0])
    centre = (slice(50, 60), slice(75, 85))
    assert np.abs(seen[centre].astype(float) - behind[centre].astype(float)).mean() > 20
    edge = (slice(50, 60), slice(0, 10))
    assert np.array_equal(seen[edge], behind[edge])


def test_default_conditions_change_nothing(paper_room) -> None:
    cam = Camera(width=160, height=120)
    a = cam.render(paper_room.world, [0, 0, 0.3], 4)
    b = cam.render(paper_room.world, [0, 0, 0.3], 4, conditions=CameraConditions())
    assert np.array_equal(a, b)


def test_exposure_and_white_balance(paper_room) -> None:
    cam = Camera(width=160, height=120, noise_sigma=0.0)
    nominal = cam.render(paper_room.world, [0, 0, 0]).astype(float)
    dark = cam.render(paper_room.world, [0, 0, 0], conditions=CameraConditions(exposure=0.5))
    assert dark.astype(float).mean() / nominal.mean() == pytest.approx(0.5, abs=0.02)
    warm = cam.render(
        paper_room.world, [0, 0, 0], conditions=CameraConditions(white_balance=(1.0, 1.0, 0.7))
    ).astype(float)
    ratio = warm.mean(axis=(0, 1)) / nominal.mean(axis=(0, 1))
    assert ratio[:2] == pytest.approx([1.0, 1.0], abs=0.01)
    assert ratio[2] == pytest.approx(0.7, abs=0.02)
    noisy = cam.render(paper_room.world, [0, 0, 0], 1, conditions=CameraConditions(noise_sigma=5))
    assert np.std(noisy.astype(float) - nominal) == pytest.approx(5.0, rel=0.15)


def test_motion_blur_smears_horizontally_by_the_turn(paper_room) -> None:
    cam = Camera(noise_sigma=0.0)
    cond = CameraConditions(exposure_time=0.02)
    sharp = cam.render(paper_room.world, [0, 0, 0], conditions=cond).astype(float)
    assert np.array_equal(sharp, cam.render(paper_room.world, [0, 0, 0]).astype(float))
    blurred = cam.render(paper_room.world, [0, 0, 0], conditions=cond, twist=(0.0, 1.0))
    blurred = blurred.astype(float)
    gx = lambda im: np.abs(np.diff(im, axis=1)).mean()  # noqa: E731
    gy = lambda im: np.abs(np.diff(im, axis=0)).mean()  # noqa: E731
    # 1 rad/s x 20 ms x f = 10 px of blur: horizontal detail goes, much more than vertical
    assert gx(blurred) < 0.6 * gx(sharp)
    assert gx(blurred) / gx(sharp) < 0.7 * gy(blurred) / gy(sharp)
    assert blurred.mean() == pytest.approx(sharp.mean(), rel=0.01)


def test_distorted_image_matches_the_calibration() -> None:
    """A thin pole seen at angle alpha lands where the calibration's distortion puts it."""
    cam = Camera(noise_sigma=0.0, dist_coeffs=RPI_V2)
    cal = cam.calibration
    assert cal.has_distortion
    assert cal.dist_coeffs == pytest.approx(RPI_V2)
    back = World(walls=[[6.0, -20.0, 6.0, 20.0]], wall_materials=MATERIAL_WALL, wall_heights=3.0)
    for alpha in (0.0, 0.25, 0.45):
        pole = World(circles=[[3.0, -3.0 * math.tan(alpha), 0.01]], circle_materials=MATERIAL_DARK)
        pole = World(circles=pole.circles, circle_materials=MATERIAL_DARK, circle_heights=3.0)
        img = cam.render(back + pole, [0, 0, 0]).astype(float)
        row = img[int(cam.height / 2)].mean(axis=1)  # along the horizon, where v is undistorted
        dark = row < 0.5 * (row.max() + row.min())
        weight = (row.max() - row) * dark
        u_seen = float(np.sum(np.arange(row.size) * weight) / weight.sum())
        u_ideal = cam.width / 2 + cam.focal * math.tan(alpha)
        u_cal = cal.distort_points([[u_ideal, cam.height / 2]])[0, 0]
        # within the pole's sampling (3-4 px wide, drawn on whole canvas columns)
        assert u_seen == pytest.approx(u_cal, abs=1.0)
        if alpha > 0.3:
            assert abs(u_cal - u_ideal) > 5  # the distortion is visible there
        assert cal.undistort_points([[u_seen, cam.height / 2]])[0, 0] == pytest.approx(
            u_ideal, abs=1.0
        )


def test_vignetting_darkens_the_corners() -> None:
    floor_only = World(walls=[[50.0, -50.0, 50.0, 50.0]], wall_heights=0.01)
    cam = Camera(noise_sigma=0.0, vignetting=0.3)
    img = cam.render(floor_only, [0, 0, 0]).astype(float)
    plain = Camera(noise_sigma=0.0).render(floor_only, [0, 0, 0]).astype(float)
    corner = img[-1, 0].mean() / plain[-1, 0].mean()
    centre = img[cam.height // 2 + 5, cam.width // 2].mean() / plain[-1, 0].mean()
    assert corner == pytest.approx(0.7, abs=0.02)
    assert centre == pytest.approx(1.0, abs=0.01)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"exposure": 0.0}, r"CameraConditions\.exposure"),
        ({"white_balance": (1.0, 1.0)}, r"CameraConditions\.white_balance"),
        ({"white_balance": (1.0, -1.0, 1.0)}, r"CameraConditions\.white_balance"),
        ({"noise_sigma": -1.0}, r"CameraConditions\.noise_sigma"),
        ({"exposure_time": -0.01}, r"CameraConditions\.exposure_time"),
    ],
)
def test_bad_conditions_raise(kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        CameraConditions(**kwargs)


def test_bad_lens_raises() -> None:
    with pytest.raises(ConfigurationError, match=r"Camera\.dist_coeffs"):
        Camera(dist_coeffs=(0.1, 0.2, 0.3))
    with pytest.raises(ConfigurationError, match=r"Camera\.vignetting"):
        Camera(vignetting=1.0)
    walls = polygon_walls([[-1, -1], [1, -1], [1, 1], [-1, 1]])
    assert World(walls).n_walls == 4
