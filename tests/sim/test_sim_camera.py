"""The pinhole camera: geometry, occlusion, textures, ORB features, bad input."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.sim.camera import Camera, render
from symloc.sim.raycast import raycast
from symloc.sim.rooms import build_room
from symloc.sim.textures import PHOTO_NAMES, PLAIN_COLORS, load_photo, material_texture
from symloc.sim.world import MATERIAL_BOARD, World

PAPER_GV = 1.5 * math.sqrt(2)  # the paper's 3 m x 3 m square
DIRECTIONS = [0.0, math.pi / 2, math.pi, -math.pi / 2]


@pytest.fixture(scope="module")
def paper_room():
    return build_room("square", PAPER_GV)


@pytest.fixture(scope="module")
def plain_room():
    return build_room("square", PAPER_GV, textured=False)


def _orb_count(img: np.ndarray) -> int:
    orb = cv2.ORB_create(500)
    return len(orb.detect(cv2.cvtColor(img, cv2.COLOR_RGB2GRAY), None))


def test_image_shape_and_seeded_noise(paper_room) -> None:
    cam = Camera(width=160, height=120)
    a = cam.render(paper_room.world, [0, 0, 0], 1)
    b = cam.render(paper_room.world, [0, 0, 0], 1)
    c = cam.render(paper_room.world, [0, 0, 0], 2)
    assert a.shape == (120, 160, 3)
    assert a.dtype == np.uint8
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    noise = a.astype(float) - c.astype(float)
    assert np.std(noise) == pytest.approx(math.sqrt(2) * 2.0, rel=0.15)


def test_boards_occlude_lower_lab_walls(paper_room) -> None:
    cam = Camera(noise_sigma=0.0)
    img = cam.render(paper_room.world, [0, 0, 0])
    # board top at 1.5 m: row cy - f (0.4 - 0.2) / 1.5; its foot: cy + f 0.2 / 1.5
    top = cam.height / 2 - cam.focal * 0.2 / 1.5
    foot = cam.height / 2 + cam.focal * 0.2 / 1.5
    board = np.array(PLAIN_COLORS[MATERIAL_BOARD], dtype=float)
    col = cam.width // 2
    for row in (math.ceil(top) + 1, round(cam.height / 2), math.floor(foot) - 1):
        assert np.all(np.abs(img[row, col].astype(float) - board) <= 4)
    assert np.any(np.abs(img[math.floor(top) - 2, col].astype(float) - board) > 10)
    floor = np.array(cam.floor_color, dtype=float)
    assert np.all(np.abs(img[math.ceil(foot) + 2, col].astype(float) - floor) <= 1)
    # the lab above the boards is a photograph: many distinct colours
    assert len(np.unique(img[: math.floor(top) - 1].reshape(-1, 3), axis=0)) > 2000


def test_textured_lab_gives_many_orb_keypoints(paper_room) -> None:
    counts = [_orb_count(render(paper_room.world, [0, 0, th], rng=0)) for th in DIRECTIONS]
    assert min(counts) >= 300, counts


def test_plain_lab_gives_few_orb_keypoints(plain_room) -> None:
    counts = [_orb_count(render(plain_room.world, [0, 0, th], rng=0)) for th in DIRECTIONS]
    assert max(counts) < 60, counts


def test_directions_look_different(paper_room) -> None:
    imgs = [render(paper_room.world, [0, 0, th], rng=0).astype(float) for th in DIRECTIONS]
    for i in range(4):
        for j in range(i + 1, 4):
            assert np.mean(np.abs(imgs[i][:150] - imgs[j][:150])) > 20


def test_gain_scales_brightness(paper_room) -> None:
    dark = Camera(gain=0.5, noise_sigma=0.0).render(paper_room.world, [0, 0, 0])
    nominal = Camera(noise_sigma=0.0).render(paper_room.world, [0, 0, 0])
    ratio = dark.astype(float).mean() / nominal.astype(float).mean()
    assert ratio == pytest.approx(0.5, abs=0.02)


def test_near_wall_fills_image_and_empty_world_is_plain() -> None:
    wall = World(walls=[[0.5, -5, 0.5, 5]], wall_heights=3.0)
    cam = Camera(noise_sigma=0.0)
    img = cam.render(wall, [0, 0, 0]).astype(float)
    foot = cam.height / 2 + cam.focal * cam.mount_height / 0.5
    col = cam.width // 2
    assert np.all(np.abs(img[: math.floor(foot) - 1, col] - np.array(PLAIN_COLORS[1])) <= 4)
    assert np.all(img[math.ceil(foot) + 1 :, col] == np.array(cam.floor_color))
    # oblique parts of the wall (image edges) are shaded darker than the head-on centre
    assert img[100, 0].mean() < img[100, col].mean() - 5
    empty = Camera(noise_sigma=0.0, width=32, height=24).render(World(), [0, 0, 0])
    assert np.all(empty[:12] == np.array(Camera().sky_color))
    assert np.all(empty[12:] == np.array(Camera().floor_color))


def test_textures() -> None:
    photo = load_photo(0, 64)
    assert photo.shape == (64, 64, 3)
    assert len(PHOTO_NAMES) >= 12
    tex = material_texture(MATERIAL_BOARD, 32).astype(float)
    assert (tex - tex.mean(axis=(0, 1))).std() < 3
    with pytest.raises(ConfigurationError, match="unknown material id 7"):
        material_texture(7, 32)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"hfov": 0.0}, r"Camera\.hfov: expected a field of view in \(0, pi\)"),
        ({"hfov": -1.0}, r"Camera\.hfov"),
        ({"hfov": math.pi}, r"Camera\.hfov"),
        ({"width": 0}, r"Camera\.width: expected an integer >= 8"),
        ({"height": 7.5}, r"Camera\.height"),
        ({"mount_height": 0.0}, r"Camera\.mount_height"),
        ({"gain": 0.0}, r"Camera\.gain"),
        ({"noise_sigma": -1.0}, r"Camera\.noise_sigma"),
        ({"floor_color": (0, 0, 300)}, r"Camera\.floor_color"),
    ],
)
def test_bad_camera_settings_raise(kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        Camera(**kwargs)


def test_intrinsics() -> None:
    cam = Camera(width=640, height=480, hfov=math.radians(90.0))
    assert cam.focal == pytest.approx(320.0)
    assert np.allclose(cam.intrinsics, [[320, 0, 320], [0, 320, 240], [0, 0, 1]])
    assert cam.vfov == pytest.approx(2 * math.atan(240 / 320))
    assert cam.column_angles[0] == pytest.approx(math.atan(319.5 / 320))


@settings(max_examples=15, deadline=None)
@given(
    name=st.sampled_from(["triangle", "square", "hexagon", "circle", "l_shaped"]),
    gv=st.floats(1.5, 5.0),
    frac=st.floats(0.0, 1.0),
    theta=st.floats(-math.pi, math.pi),
    col=st.integers(0, 159),
)
def test_camera_agrees_with_ray_casting(
    name: str, gv: float, frac: float, theta: float, col: int
) -> None:
    """The floor/board boundary in any column sits where the ray-cast distance puts it."""
    room = build_room(name, gv, furniture=0)
    pts = room.positions_inside(20, margin=0.3)
    x, y = pts[int(frac * 19)]
    cam = Camera(width=160, height=120, noise_sigma=0.0)
    img = cam.render(room.world, [x, y, theta]).astype(float)
    alpha = cam.column_angles[col]
    d = raycast(room.world, [x, y], [theta + alpha])[0]
    foot = cam.height / 2 + cam.focal * cam.mount_height / (d * math.cos(alpha))
    floor = np.array(cam.floor_color, dtype=float)
    below = math.ceil(foot - 0.5) + 1
    above = math.floor(foot - 0.5) - 1
    if below < cam.height:
        assert np.all(img[below, col] == floor)
    if 0 <= above < cam.height:
        assert np.any(img[above, col] != floor)
