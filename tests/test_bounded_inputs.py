"""Inputs bounded before work (issue 31): special files, YAML depth and aliases, sizes, names.

Each loader of a whole file (map YAML, world file, params files, vocabulary, images) refuses a
FIFO (which used to hang the reader), /dev/zero (read without end: its size is 0), a folder,
deeply nested YAML (a RecursionError before) and a file larger than its cap, with its own
error family and a message naming the file.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from symloc.errors import (
    ConfigurationError,
    DataFormatError,
    MapFileError,
    VocabularyFileError,
    WorldError,
)
from symloc.files.bounded import MAX_YAML_ALIASES, MAX_YAML_DEPTH
from symloc.grid import OccupancyGrid
from symloc.grid.map_io import load_map, read_map_yaml, save_map
from symloc.image_header import read_image_file
from symloc.mcl.params import AmclParams
from symloc.ros.nav2_params import read_params_block
from symloc.ros.params import NodeParams
from symloc.sim.world_file import load_world_file
from symloc.vision.vocabulary_io import read_vocabulary

LOADERS: dict[str, tuple[Callable[[Path], Any], type[Exception]]] = {
    "map YAML": (load_map, MapFileError),
    "world file": (load_world_file, WorldError),
    "node params": (NodeParams.from_yaml, ConfigurationError),
    "nav2 params block": (read_params_block, ConfigurationError),
    "amcl params": (AmclParams.from_nav2_yaml, ConfigurationError),
    "vocabulary": (read_vocabulary, VocabularyFileError),
    "image": (read_image_file, DataFormatError),
}


def _special(tmp_path: Path, kind: str) -> Path:
    if kind == "fifo":
        path = tmp_path / "pipe.yaml"
        os.mkfifo(path)
        return path
    if kind == "folder":
        path = tmp_path / "folder.yaml"
        path.mkdir()
        return path
    return Path("/dev/zero")


@pytest.mark.parametrize("kind", ["fifo", "/dev/zero", "folder"])
@pytest.mark.parametrize("loader", list(LOADERS))
def test_special_files_are_refused_at_once(tmp_path: Path, loader: str, kind: str) -> None:
    if kind == "/dev/zero" and not Path("/dev/zero").exists():
        pytest.skip("no /dev/zero")
    load, error = LOADERS[loader]
    path = _special(tmp_path, kind)
    t0 = time.monotonic()
    with pytest.raises(error, match=r"(a FIFO|a character device|a folder); expected a regular"):
        load(path)
    assert time.monotonic() - t0 < 5.0


def _nested(depth: int) -> str:
    return "key: " + "[" * depth + "]" * depth + "\n"


def _laughs() -> str:
    lines = ["a0: &a0 {x: 1, y: 2}"]
    for i in range(1, 12):
        refs = ", ".join(f"k{j}: *a{i - 1}" for j in range(30))
        lines.append(f"a{i}: &a{i} {{{refs}}}")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (_nested(100_000), f"nested deeper than {MAX_YAML_DEPTH} levels"),
        (_nested(MAX_YAML_DEPTH + 1), f"nested deeper than {MAX_YAML_DEPTH} levels"),
        (_laughs(), f"more than {MAX_YAML_ALIASES} aliases"),
    ],
    ids=["100000 levels", "65 levels", "billion laughs"],
)
@pytest.mark.parametrize(
    "loader", ["map YAML", "world file", "node params", "nav2 params block", "amcl params"]
)
def test_yaml_nesting_and_aliases_are_bounded(
    tmp_path: Path, loader: str, text: str, match: str
) -> None:
    load, error = LOADERS[loader]
    path = tmp_path / "deep.yaml"
    path.write_text(text)
    with pytest.raises(error, match=rf"deep\.yaml.*{match}|{match}"):
        load(path)


def test_moderate_nesting_still_loads(tmp_path: Path) -> None:
    """A params file nested a few levels (as nav2's are) is fine."""
    path = tmp_path / "p.yaml"
    path.write_text("symloc:\n  ros__parameters:\n    amcl: {alpha1: 0.3}\n")
    assert NodeParams.from_yaml(path).amcl.alpha1 == 0.3


def test_a_world_file_of_a_million_vertices_is_refused_unparsed(tmp_path: Path) -> None:
    path = tmp_path / "huge.yaml"
    vertices = ", ".join(f"[{i % 7}.0, {i % 5}.0]" for i in range(1_000_000))
    path.write_text(f"name: huge\nroom: {{polygon: [{vertices}]}}\n")
    t0 = time.monotonic()
    with pytest.raises(WorldError, match=r"huge\.yaml: the world file has [\d,]+ bytes; at most"):
        load_world_file(path)
    assert time.monotonic() - t0 < 1.0


def test_an_image_name_over_255_bytes_is_a_clean_error(tmp_path: Path) -> None:
    y = save_map(OccupancyGrid(np.zeros((4, 4), np.int8), 0.05), tmp_path / "m")
    lines = y.read_text().splitlines()
    lines[0] = "image: " + "x" * 300 + ".pgm"
    y.write_text("\n".join(lines) + "\n")
    with pytest.raises(MapFileError, match=r"field 'image' must be a file name of at most 255"):
        read_map_yaml(y)
    lines[0] = "image: 'a\\0b.pgm'"
    y.write_text("\n".join(lines).replace("'a\\0b.pgm'", '"a\\0b.pgm"') + "\n")
    with pytest.raises(MapFileError, match="no NUL byte"):
        read_map_yaml(y)


def test_a_path_name_too_long_is_a_clean_error(tmp_path: Path) -> None:
    with pytest.raises(MapFileError, match="name of map YAML is too long"):
        load_map(tmp_path / ("y" * 300 + ".yaml"))
    with pytest.raises(WorldError, match="too long"):
        load_world_file(tmp_path / ("w" * 300 + ".yaml"))


def test_vocabulary_training_skips_images_too_small_with_a_count(tmp_path: Path) -> None:
    """1 x 1 and 1 x 500 photos crashed `vocab train` in OpenCV's pyramid (issue 31)."""
    import cv2

    from symloc.vision.orb import OrbExtractor, OrbSettings
    from symloc.vision.vocabulary import Vocabulary

    rng = np.random.default_rng(0)
    for i in range(3):
        cv2.imwrite(str(tmp_path / f"ok{i}.png"), (rng.random((120, 160)) * 255).astype(np.uint8))
    cv2.imwrite(str(tmp_path / "dot.png"), np.zeros((1, 1), np.uint8))
    cv2.imwrite(str(tmp_path / "line.png"), np.zeros((1, 500), np.uint8))
    cv2.imwrite(str(tmp_path / "small.png"), np.zeros((40, 40), np.uint8))
    ext = OrbExtractor(OrbSettings(n_features=50))
    assert len(ext.extract(np.zeros((1, 500), np.uint8))) == 0  # no OpenCV error
    with pytest.warns(UserWarning, match=r"skipped 3 image\(s\) smaller than 63 x 63 pixels"):
        voc = Vocabulary.train_from_folder(tmp_path, extractor=ext, k=2, L=2, progress=False)
    assert voc.n_words >= 1
