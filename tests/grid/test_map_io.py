"""Tests of map_server YAML + image reading and writing (symloc.grid.map_io)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from symloc.errors import MapFileError
from symloc.grid import OccupancyGrid
from symloc.grid.map_io import (
    MapMetadata,
    grid_to_image,
    image_to_grid,
    load_map,
    read_map_yaml,
    save_map,
)

# The example YAML of nav2_map_server's documentation (map_server README / nav2 docs).
NAV2_DOC_YAML = """image: testmap.png
mode: trinary
resolution: 0.1
origin: [2.0, 3.0, 1.0]
negate: 0
occupied_thresh: 0.65
free_thresh: 0.196
"""

# The example of the ROS 1 map_server wiki page.
ROS_WIKI_YAML = """image: testmap.png
resolution: 0.1
origin: [0.0, 0.0, 0.0]
occupied_thresh: 0.65
free_thresh: 0.196
negate: 0
"""


def _write_pair(tmp_path: Path, text: str, image: np.ndarray, name: str = "testmap.png") -> Path:
    assert cv2.imwrite(str(tmp_path / name), image)
    y = tmp_path / "map.yaml"
    y.write_text(text)
    return y


def _image() -> np.ndarray:
    # 3 rows x 4 cols, top row first: black (occupied), white (free), 205 (unknown)
    return np.array([[0, 254, 205, 0], [254, 254, 254, 205], [205, 0, 254, 254]], dtype=np.uint8)


def test_nav2_doc_yaml_is_read_with_its_values(tmp_path: Path) -> None:
    y = _write_pair(tmp_path, NAV2_DOC_YAML, _image())
    meta = read_map_yaml(y)
    assert meta.image == tmp_path / "testmap.png"
    assert meta.resolution == 0.1
    assert meta.origin == (2.0, 3.0, 1.0)
    assert meta.mode == "trinary"
    assert meta.negate is False
    grid = load_map(y)
    assert grid.resolution == pytest.approx(0.1)
    np.testing.assert_allclose(grid.origin, [2.0, 3.0, 1.0])
    # row 0 of the grid is the image's bottom row
    np.testing.assert_array_equal(grid.data, [[-1, 100, 0, 0], [0, 0, 0, -1], [100, 0, -1, 100]])


def test_ros_wiki_yaml_defaults_to_trinary(tmp_path: Path) -> None:
    y = _write_pair(tmp_path, ROS_WIKI_YAML, _image())
    grid = load_map(y)
    assert read_map_yaml(y).mode == "trinary"
    assert grid.data[2, 0] == 100
    assert grid.data[2, 1] == 0
    assert grid.data[2, 2] == -1


def test_round_trip_trinary_through_nav2_file_is_identical(tmp_path: Path) -> None:
    y = _write_pair(tmp_path, NAV2_DOC_YAML, _image())
    grid = load_map(y)
    out = save_map(grid, tmp_path / "out" / "copy")
    assert out.name == "copy.yaml"
    image = read_map_yaml(out).image  # copy.<write id>.pgm
    assert image.parent == tmp_path / "out"
    assert image.name.startswith("copy.")
    assert image.suffix == ".pgm"
    assert image.is_file()
    again = load_map(out)
    np.testing.assert_array_equal(again.data, grid.data)
    np.testing.assert_allclose(again.origin, grid.origin)
    assert again.resolution == grid.resolution
    # the written image is the nav2 map_saver's trinary image, pixel for pixel
    np.testing.assert_array_equal(cv2.imread(str(image), 0), _image())


@settings(max_examples=25, deadline=None)
@given(
    data=arrays(
        np.int8, st.tuples(st.integers(1, 12), st.integers(1, 12)), elements=st.integers(-1, 100)
    ),
    yaw=st.floats(-3.1, 3.1),
)
def test_raw_mode_round_trips_every_value(tmp_path_factory, data, yaw) -> None:
    tmp = tmp_path_factory.mktemp("raw")
    grid = OccupancyGrid(data, 0.05, np.array([-1.5, 2.25, yaw]))
    y = save_map(grid, tmp / "m.yaml", mode="raw")
    back = load_map(y)
    np.testing.assert_array_equal(back.data, grid.data)
    assert back.origin[2] == pytest.approx(yaw)


def test_scale_mode_keeps_classes_and_unknown_transparency(tmp_path: Path) -> None:
    data = np.array([[-1, 0, 100], [10, 50, 90]], dtype=np.int8)
    grid = OccupancyGrid(data, 0.1)
    y = save_map(grid, tmp_path / "s", mode="scale")
    assert read_map_yaml(y).image.suffix == ".png"
    assert read_map_yaml(y).image.is_file()
    back = load_map(y)
    assert back.data[0, 0] == -1
    assert back.data[0, 1] == 0
    assert back.data[0, 2] == 100
    # nav2 scale semantics: rint(100 (occ - free) / (occ_t - free)) between the thresholds
    occ = 1.0 - np.rint(255 * 0.5) / 255.0
    assert back.data[1, 1] == int(np.rint((occ - 0.196) / (0.65 - 0.196) * 100))
    assert back.data[1, 0] == 0
    assert back.data[1, 2] == 100


def test_negate_swaps_black_and_white(tmp_path: Path) -> None:
    y = _write_pair(tmp_path, NAV2_DOC_YAML.replace("negate: 0", "negate: 1"), _image())
    grid = load_map(y)
    assert grid.data[2, 0] == 0  # black pixel is free when negated
    assert grid.data[2, 1] == 100


def test_colour_image_is_averaged(tmp_path: Path) -> None:
    img = np.zeros((1, 2, 3), np.uint8)
    img[0, 1] = 254
    y = _write_pair(tmp_path, NAV2_DOC_YAML, img)
    np.testing.assert_array_equal(load_map(y).data, [[100, 0]])


def test_image_to_grid_trinary_includes_alpha() -> None:
    meta = MapMetadata(Path("x.png"), 0.1, (0, 0, 0), 0.65, 0.196)
    bgra = np.zeros((1, 1, 4), np.uint8)  # black, fully transparent: mean with alpha 0 -> occ 1
    assert image_to_grid(bgra, meta)[0, 0] == 100
    assert grid_to_image(OccupancyGrid(np.array([[55]]), 0.1), "trinary")[0, 0] == 205


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("image: [unclosed", "not valid YAML"),
        ("- a\n- b\n", "expected a YAML mapping"),
        (ROS_WIKI_YAML.replace("image: testmap.png\n", ""), "missing required field 'image'"),
        (
            ROS_WIKI_YAML.replace("resolution: 0.1", "resolution: -0.1"),
            "'resolution' must be 1e-06",
        ),
        (
            ROS_WIKI_YAML.replace("resolution: 0.1", "resolution: 1e-300"),
            r"'resolution' must be 1e-06\.\.10000 m/pixel, got 1e-300",
        ),
        (
            ROS_WIKI_YAML.replace("origin: [0.0, 0.0, 0.0]", "origin: [1e300, 0.0, 0.0]"),
            "'origin' must have",
        ),
        (
            ROS_WIKI_YAML.replace("resolution: 0.1", "resolution: abc"),
            "'resolution' must be a number",
        ),
        (
            ROS_WIKI_YAML.replace("origin: [0.0, 0.0, 0.0]", "origin: [0.0, 0.0]"),
            "'origin' must be 3",
        ),
        (ROS_WIKI_YAML.replace("origin: [0.0, 0.0, 0.0]\n", ""), "missing required field 'origin'"),
        (
            ROS_WIKI_YAML.replace("occupied_thresh: 0.65", "occupied_thresh: 1.5"),
            "'occupied_thresh' must be in \\[0, 1\\]",
        ),
        (
            ROS_WIKI_YAML.replace("free_thresh: 0.196", "free_thresh: -0.1"),
            "'free_thresh' must be in \\[0, 1\\]",
        ),
        (
            ROS_WIKI_YAML.replace("free_thresh: 0.196", "free_thresh: 0.7"),
            "'free_thresh' \\(0.7\\) must be smaller",
        ),
        (ROS_WIKI_YAML.replace("free_thresh: 0.196\n", ""), "missing required field 'free_thresh'"),
        (ROS_WIKI_YAML.replace("negate: 0", "negate: 2"), "'negate' must be 0, 1"),
        (ROS_WIKI_YAML + "mode: fancy\n", "'mode' must be one of"),
        (ROS_WIKI_YAML + "width: -3\n", "'width' must be a positive integer"),
    ],
)
def test_malformed_yaml_names_the_field(tmp_path: Path, text: str, match: str) -> None:
    y = _write_pair(tmp_path, text, _image())
    with pytest.raises(MapFileError, match=match):
        load_map(y)


def test_missing_yaml_and_missing_image(tmp_path: Path) -> None:
    with pytest.raises(MapFileError, match="cannot read map YAML"):
        load_map(tmp_path / "nope.yaml")
    (tmp_path / "map.yaml").write_text(ROS_WIKI_YAML)
    with pytest.raises(MapFileError, match="field 'image': file not found"):
        load_map(tmp_path / "map.yaml")


def test_undecodable_image(tmp_path: Path) -> None:
    (tmp_path / "testmap.png").write_bytes(b"not an image")
    (tmp_path / "map.yaml").write_text(ROS_WIKI_YAML)
    with pytest.raises(MapFileError, match=r"testmap\.png\): not an image format"):
        load_map(tmp_path / "map.yaml")
    # a valid PNG header, then garbage: OpenCV cannot decode it
    _, png = cv2.imencode(".png", np.zeros((5, 4), np.uint8))
    (tmp_path / "testmap.png").write_bytes(png.tobytes()[:40] + b"\x00" * 30)
    with pytest.raises(MapFileError, match="cannot decode image"):
        load_map(tmp_path / "map.yaml")


@pytest.mark.parametrize(
    ("data", "match"),
    [
        (b"P5\n65535 65535\n65535\n" + b"\x00" * 64, "65535 x 65535"),
        (b"P2\n100000 100000\n255\n0 0 0\n", "100000 x 100000"),
    ],
)
def test_huge_declared_images_are_refused_before_decoding(
    tmp_path: Path, data: bytes, match: str
) -> None:
    import tracemalloc

    (tmp_path / "big.pgm").write_bytes(data)
    (tmp_path / "map.yaml").write_text(ROS_WIKI_YAML.replace("testmap.png", "big.pgm"))
    tracemalloc.start()
    with pytest.raises(MapFileError, match=rf"big\.pgm\): pnm header declares {match}"):
        load_map(tmp_path / "map.yaml")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 5_000_000


def test_max_pixels_and_blocks(tmp_path: Path) -> None:
    img = np.full((300, 200), 254, np.uint8)
    img[:10] = 0
    y = _write_pair(tmp_path, ROS_WIKI_YAML, img)
    with pytest.raises(MapFileError, match="at most 59,999 allowed"):
        load_map(y, max_pixels=59_999)
    import symloc.grid.map_io as mio

    whole = load_map(y)
    old = mio._BLOCK_PIXELS
    mio._BLOCK_PIXELS = 999  # several blocks of rows give the same grid
    try:
        np.testing.assert_array_equal(load_map(y).data, whole.data)
    finally:
        mio._BLOCK_PIXELS = old


def test_wrong_image_size_names_width_and_height(tmp_path: Path) -> None:
    y = _write_pair(tmp_path, ROS_WIKI_YAML + "width: 5\nheight: 3\n", _image())
    with pytest.raises(
        MapFileError, match=r"field 'width' is 5 pixels but image testmap\.png is 4"
    ):
        load_map(y)
    y = _write_pair(tmp_path, ROS_WIKI_YAML + "width: 4\nheight: 7\n", _image())
    with pytest.raises(MapFileError, match="field 'height' is 7 pixels"):
        load_map(y)


def test_save_rejects_bad_mode_format_and_thresholds(tmp_path: Path) -> None:
    grid = OccupancyGrid(np.zeros((2, 2), np.int8), 0.1)
    with pytest.raises(MapFileError, match="mode: expected one of"):
        save_map(grid, tmp_path / "a", mode="binary")
    with pytest.raises(MapFileError, match="image_format: expected 'pgm' or 'png'"):
        save_map(grid, tmp_path / "a", image_format="jpg")
    with pytest.raises(MapFileError, match="mode 'scale' needs transparency"):
        save_map(grid, tmp_path / "a", mode="scale", image_format="pgm")
    with pytest.raises(MapFileError, match="'occupied_thresh' must be in"):
        save_map(grid, tmp_path / "a", occupied_thresh=2.0)
