"""The one place record: the localizer's geometry plus the visual map's views."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import symloc.localizer
import symloc.localizer.types
import symloc.vision
from symloc.errors import ConfigurationError
from symloc.localizer.vision_store import VisionPlaceStore
from symloc.symmetry.order import SymmetryOrder
from symloc.vision.bow import BowVector
from symloc.vision.orb import OrbFeatures
from symloc.vision.place import UNANCHORED_LABEL, Place, PlaceImage
from symloc.vision.visual_map import VisualMap


def _image(j: int) -> PlaceImage:
    rng = np.random.default_rng(j)
    kp = np.column_stack(
        [rng.uniform(0, 60, (5, 2)), np.full(5, 31.0), np.zeros(5), np.ones(5), np.zeros(5)]
    ).astype(np.float32)
    desc = rng.integers(0, 256, (5, 32), dtype=np.uint8)
    feats = OrbFeatures.from_arrays(kp, desc, (64, 48))
    bow = BowVector(np.array([j, j + 10], np.int32), np.array([0.5, 0.5]))
    return PlaceImage(j, -j * math.pi / 2, feats, bow)


def test_one_class_under_every_name() -> None:
    assert symloc.localizer.Place is Place
    assert symloc.localizer.types.Place is Place
    assert symloc.vision.Place is Place


def test_geometry_only_place_keeps_m_without_images() -> None:
    p = Place(1, np.array([1.0, 2.0]), heading0=0.3, m=4, order=4, gv_distance=1.5)
    assert p.images == ()
    assert p.m == 4
    assert p.kind == "polygon"
    assert p.heading_reliable
    assert p.label is None
    assert p.pose.tolist() == [1.0, 2.0, 0.3]
    assert p.order == SymmetryOrder.finite(4)  # an int is a finite order


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"center": np.zeros(3)}, r"Place\.center: expected shape \(2,\)"),
        ({"m": -1}, r"Place\.m: expected >= 0"),
        ({"order": 0}, r"Place\.order: expected a SymmetryOrder or an integer k >= 1, got 0"),
        ({"images": (_image(0),)}, r"Place\.images: 1 views for m = 4 directions \(place 5\)"),
    ],
)
def test_bad_fields_are_named(kwargs: dict[str, object], match: str) -> None:
    args: dict[str, object] = {
        "place_id": 5,
        "center": np.zeros(2),
        "heading0": 0.0,
        "m": 4,
        "order": 4,
        "gv_distance": 1.0,
    }
    with pytest.raises(ConfigurationError, match=match):
        Place(**{**args, **kwargs})  # type: ignore[arg-type]


def test_the_map_and_the_store_give_one_place(tmp_path: Path) -> None:
    images = [_image(j) for j in range(4)]
    with VisualMap(tmp_path / "m.db") as vm:
        sq = vm.add_place(kind="square", order=4, gv_distance=1.5, pose=(1, 2, 0.3), images=images)
        ci = vm.add_place(
            kind="circle",
            order=4,
            gv_distance=2.0,
            pose=(5, 6, -0.2),
            images=images,
            label=UNANCHORED_LABEL,
        )
        place = vm.place(sq)
        assert (place.place_id, place.kind, place.m) == (sq, "square", 4)
        assert place.order == SymmetryOrder.finite(4)
        assert place.center.tolist() == [1.0, 2.0]
        assert place.heading0 == 0.3
        assert place.heading_reliable
        assert [im.direction for im in place.images] == [0, 1, 2, 3]
        circle = vm.place(ci, with_images=False)
        assert not circle.heading_reliable
        assert circle.order == SymmetryOrder.CIRCLE  # the column holds m; kind says circle
        store = VisionPlaceStore(vm, vocabulary=None, intrinsics=np.eye(3))
        by_id = {p.place_id: p for p in store.all_places()}
        assert by_id[sq].order == SymmetryOrder.finite(4)
        assert by_id[ci].order == SymmetryOrder.CIRCLE  # one reading in every layer
        assert by_id[ci].m == 4
        assert not by_id[ci].heading_reliable
