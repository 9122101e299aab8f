"""The node's glue to the one builder (symloc.ros.assemble.make_localizer)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from symloc.grid import OccupancyGrid
from symloc.localizer.places import MemoryPlaces
from symloc.ros import assemble
from symloc.ros.params import NodeParams


class _KeyframePlaces(MemoryPlaces):
    """A place store that also holds keyframes (as a visual map of schema 2 does)."""

    def keyframe_count(self) -> int:
        return 3

    def expected_counts(self, poses: Any) -> Any:
        raise AssertionError("not called while building")

    def verify(self, poses: Any, image: Any) -> Any:
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
