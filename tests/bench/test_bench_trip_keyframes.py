"""Keyframes recorded along the simulated mapping trip (an option of build_scenario)."""

from __future__ import annotations

import inspect
import math
from pathlib import Path

import numpy as np
import pytest

from symloc.bench.scenario import build_scenario
from symloc.errors import ConfigurationError
from symloc.geometry import compose, inverse, wrap_angle
from symloc.vision.verification import verify_hypotheses


def test_keyframes_are_off_by_default() -> None:
    assert inspect.signature(build_scenario).parameters["keyframes"].default is None
    with pytest.raises(ConfigurationError, match="SLAM mapping trips only"):
        build_scenario("square", map_source="raster", keyframes=True)
    # the heading alignment is off by default too, and needs keyframes
    assert inspect.signature(build_scenario).parameters["align_headings"].default is False
    with pytest.raises(ConfigurationError, match="align_headings"):
        build_scenario("square", align_headings=True)


def test_trip_keyframes_verify_the_true_copy(tmp_path: Path) -> None:
    scen = build_scenario("square", rng=0, workdir=tmp_path, keyframes=True)
    try:
        vm = scen.store.visual_map
        assert scen.n_keyframes == vm.keyframe_count() >= 5
        note = scen.notes[-1]
        assert "keyframes" in note
        assert "KiB per m2" in note
        per_m2 = vm.keyframe_bytes() / float(scen.room.area)
        assert per_m2 < 100 * 1024, note
        ids, poses = vm.keyframe_poses()
        world_from_map = inverse(scen.map_from_world)
        centre = np.asarray(scen.room.center, np.float64)
        image_at = scen.image_at(np.random.default_rng(1))
        rng = np.random.default_rng(2)
        tally = {"correct": 0, "none": 0, "wrong": 0}
        for k in range(0, len(ids), max(1, len(ids) // 4)):
            # near a keyframe of the trip, seen again in the query session
            kf_world = np.asarray(compose(world_from_map, poses[k]), np.float64)
            truth = kf_world + np.array([*rng.uniform(-0.1, 0.1, 2), rng.uniform(-0.1, 0.1)])
            copies = []
            for j in range(4):
                a = j * math.pi / 2
                c, s = math.cos(a), math.sin(a)
                d = truth[:2] - centre
                w = np.array(
                    [centre[0] + c * d[0] - s * d[1], centre[1] + s * d[0] + c * d[1], truth[2] + a]
                )
                copies.append(scen.to_map(w))
            dec = verify_hypotheses(
                np.array(copies), image_at(truth), vm, scen.store.vocabulary, scen.camera
            )
            if dec.index is None:
                tally["none"] += 1
            elif dec.index == 0:
                tally["correct"] += 1
                assert dec.pose is not None
                heading_err = float(wrap_angle(dec.pose[2] - scen.to_map(truth)[2]))
                assert abs(heading_err) < math.radians(4.0)
            else:
                tally["wrong"] += 1
        print(tally)
        assert tally["wrong"] == 0
        assert tally["correct"] >= 3
    finally:
        scen.close()
