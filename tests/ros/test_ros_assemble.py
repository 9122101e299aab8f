"""The node's glue to the one builder (symloc.ros.assemble.make_localizer)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.localizer.places import MemoryPlaces
from symloc.ros import assemble
from symloc.ros.params import NodeParams


class _KeyframePlaces(MemoryPlaces):
    """A place store that also holds keyframes (as a visual map of schema 2 does)."""

    def keyframe_count(self) -> int:
        return 3

    def expected_counts(self, poses: Any, reach: float = 0.0) -> Any:
        raise AssertionError("not called while building")

    def verify(
        self,
        poses: Any,
        image: Any,
        reach: float = 0.0,
        *,
        refine: bool = False,
        round_centre: Any = None,
    ) -> Any:
        raise AssertionError("not called while building")


@pytest.mark.parametrize(
    ("store", "has_keyframes"), [(_KeyframePlaces(), True), (MemoryPlaces(), False)]
)
def test_a_visual_map_with_keyframes_reaches_the_localizer(
    monkeypatch: pytest.MonkeyPatch, store: MemoryPlaces, has_keyframes: bool
) -> None:
    seen: dict[str, Any] = {}
    started: list[bool] = []

    def build(grid: Any, settings: Any, **kwargs: Any) -> Any:
        seen.update(kwargs, settings=settings)
        return SimpleNamespace(reset_global=lambda: started.append(True))

    monkeypatch.setattr(assemble, "build_localizer", build)
    params = NodeParams.from_dict({"localizer": {"decide_here": True}})
    room = np.zeros((8, 8), np.int8)
    room[0] = 100  # a wall: a map with no occupied cell is refused
    assemble.make_localizer(OccupancyGrid(room, 0.05), params, places=store)
    assert seen["places"] is store
    assert (seen["keyframes"] is store) is has_keyframes
    assert seen["settings"].localizer.decide_here
    assert started == [True]  # a global start: nothing earned


def test_a_visual_maps_declared_round_map_error_reaches_the_claim_gate(tmp_path: Path) -> None:
    """A round room's measured map rotation (the mapping gyro's drift fitted to the images)
    and placement (its trip's distortion) are what the node's claim gate assumes, as the
    bench's (not the 1.9 deg default)."""
    import math

    from symloc.localizer.claim import ClaimConfig
    from symloc.vision import VisualMap
    from symloc.vision.gyro_drift import META_KEY, POSITION_META_KEY

    room = np.zeros((8, 8), np.int8)
    room[0] = 100
    params = NodeParams.from_dict({})
    with VisualMap(tmp_path / "places.db", create=True) as vm:
        store = SimpleNamespace(visual_map=vm, all_places=list)
        gate = assemble.make_localizer(OccupancyGrid(room, 0.05), params, places=store).claim_gate
        assert gate is not None
        assert gate.config.map_rotation_std == ClaimConfig().map_rotation_std
        vm.set_meta(META_KEY, repr(math.radians(0.3)))
        gate = assemble.make_localizer(OccupancyGrid(room, 0.05), params, places=store).claim_gate
        assert gate is not None
        assert gate.config.map_rotation_std == pytest.approx(math.radians(0.3))
        # how far the map is placed, from its trip's distortion: the gate's map error floor
        vm.set_meta(POSITION_META_KEY, repr(0.12))
        gate = assemble.make_localizer(OccupancyGrid(room, 0.05), params, places=store).claim_gate
        assert gate is not None
        assert gate.config.map_std_xy == pytest.approx(0.12)
        vm.set_meta(META_KEY, "a lot")
        with pytest.raises(ConfigurationError, match=META_KEY):
            assemble.make_localizer(OccupancyGrid(room, 0.05), params, places=store)


# ------------------------------------------------- files named by parameters (issue 31)


def _bad_files(tmp_path: Path) -> dict[str, tuple[dict[str, str], str]]:
    """Parameters naming a visual map or vocabulary that cannot be used, and the error."""
    import sqlite3

    from symloc.vision import VisualMap
    from symloc.vision.visual_map import SCHEMA_VERSION

    future = tmp_path / "future.db"
    VisualMap(future, create=True).close()
    with sqlite3.connect(future) as con:
        con.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    garbage = tmp_path / "garbage.db"
    garbage.write_bytes(b"\x00not a database" * 100)
    voc = tmp_path / "garbage.voc"
    voc.write_bytes(b"SYMVOC\x00\x01garbage")
    good = tmp_path / "places.db"
    VisualMap(good, create=True).close()
    return {
        "missing visual map": (
            {"visual_map": str(tmp_path / "plaecs.db")},
            r"visual_map: .*plaecs\.db does not exist",
        ),
        "visual map of a future schema": (
            {"visual_map": str(future)},
            rf"visual_map: .*future\.db: schema version {SCHEMA_VERSION + 1} is newer",
        ),
        "garbage visual map": ({"visual_map": str(garbage)}, r"visual_map: .*garbage\.db"),
        "folder as visual map": ({"visual_map": str(tmp_path)}, "visual_map: "),
        "missing vocabulary": (
            {"visual_map": str(good), "vocabulary": str(tmp_path / "voc.bin")},
            r"vocabulary: .*voc\.bin",
        ),
        "garbage vocabulary": (
            {"visual_map": str(good), "vocabulary": str(voc)},
            r"vocabulary: .*garbage\.voc",
        ),
        "garbage vocabulary without a visual map": (
            {"vocabulary": str(voc)},
            r"vocabulary: .*garbage\.voc",
        ),
    }


BAD_FILES = [
    "missing visual map",
    "visual map of a future schema",
    "garbage visual map",
    "folder as visual map",
    "missing vocabulary",
    "garbage vocabulary",
    "garbage vocabulary without a visual map",
]


@pytest.mark.parametrize("case", BAD_FILES)
def test_check_files_names_the_parameter_and_the_reason(tmp_path: Path, case: str) -> None:
    changes, match = _bad_files(tmp_path)[case]
    with pytest.raises(ConfigurationError, match=match):
        assemble.check_files(NodeParams(**changes))


def test_check_files_accepts_usable_files(tmp_path: Path) -> None:
    from symloc.vision import VisualMap

    VisualMap(tmp_path / "places.db", create=True).close()
    assemble.check_files(NodeParams(visual_map=str(tmp_path / "places.db")))
    assemble.check_files(NodeParams())  # nothing named: nothing to check
    # building a visual map: a file not there yet is created where its folder exists
    mapping = NodeParams(visual_map=str(tmp_path / "new.db"), mode="build_visual_map")
    assemble.check_files(mapping)


def test_replay_fails_at_once_on_a_bad_visual_map(tmp_path: Path) -> None:
    from symloc.ros.replay import replay_bag

    params = NodeParams(visual_map=str(tmp_path / "missing.db"))
    with pytest.raises(ConfigurationError, match=r"visual_map: .*missing\.db does not exist"):
        replay_bag(tmp_path / "no_bag_needed", params)
