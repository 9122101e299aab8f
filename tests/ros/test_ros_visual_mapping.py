"""The node's visual-map building mode, in the loop and from a recorded bag."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from symloc.bench.sim_record import record_sim_run
from symloc.ros.params import NodeParams
from symloc.ros.replay import replay_bag
from symloc.vision import VisualMap


def _places(path: Path) -> list[tuple[str, str, int]]:
    vm = VisualMap(path, create=False)
    try:
        out = []
        for pid in vm.place_ids():
            p = vm.place(pid, with_images=False)
            out.append((p.kind, str(p.order), int(p.m)))
        return out
    finally:
        vm.close()


@pytest.mark.slow
def test_build_visual_map_mode_in_the_loop_and_from_the_bag(tmp_path: Path) -> None:
    rec = record_sim_run(tmp_path / "run", seed=2, mode="build_visual_map", max_time=60.0)
    built = rec.assets / "places_built.db"
    assert _places(built) == [("polygon", "4", 4)]
    assert rec.final.status.value == "ambiguous"
    assert "new visual map built" in rec.final.reason
    assert rec.counts["/camera/image_raw"] >= 4
    # the same visual map, built again from the recorded bag
    params = NodeParams.from_yaml(rec.params_path)
    again = tmp_path / "from_bag.db"
    res = replay_bag(
        rec.bag, dataclasses.replace(params, visual_map=str(again), mode="build_visual_map")
    )
    assert any("new visual map built" in s for s in res.steps)
    assert _places(again) == [("polygon", "4", 4)]
