"""End-to-end: Algorithm 2 and the full localizer on the simulator with the real parts."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("symloc.sim.camera", reason="the simulator's camera is not available")
pytest.importorskip("symloc.symmetry", reason="the symmetry judgement is not available")
pytest.importorskip("symloc.vision.orientation", reason="the orientation decision is missing")

from symloc.bench.scenario import build_scenario, run_plain_amcl, run_symloc
from symloc.localizer.types import Status


def test_go_to_centre_in_the_square_stops_near_the_centre_without_hitting_anything():
    from symloc.bench.episode import RobotBody, go_to_centre
    from symloc.localizer.adapters import ReportJudge
    from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
    from symloc.sim.robot import DiffDriveRobot
    from symloc.sim.rooms import build_room
    from symloc.symmetry import SymmetryConfig, judge_symmetry

    rng = np.random.default_rng(3)
    room = build_room("square", 3.0 / math.sqrt(2.0), lab=True)
    judge = ReportJudge(judge_symmetry, config=SymmetryConfig.from_lidar(RPLIDAR_A2))
    body = RobotBody(DiffDriveRobot([1.1, -0.9, 2.5], rng=rng, world=room.world))
    run = go_to_centre(
        body,
        lambda p: simulate_scan(room.world, p, RPLIDAR_A2, rng),
        judge,
        true_centre=room.center,
        dt=0.1,
    )
    assert run.phase == "done"
    assert run.error < 0.015
    assert body.collisions == 0
    assert judge.errors == 0


@pytest.mark.parametrize("textured", [True, False])
def test_kidnapped_robot_in_the_square(tmp_path, textured):
    rng = np.random.default_rng(11)
    # the textured run maps with SLAM, the untextured one with the rasterised ground truth
    source = "slam" if textured else "raster"
    scen = build_scenario("square", textured=textured, rng=rng, workdir=tmp_path, map_source=source)
    try:
        assert scen.mapped is not None
        start = scen.random_pose(rng)
        s = run_symloc(scen, start, np.random.default_rng(1))
        statuses = [e.status for e in s.episode.estimates]
        assert Status.GOING_TO_CENTRE in statuses
        # never a pose before it was earned
        first_tracking = statuses.index(Status.TRACKING) if Status.TRACKING in statuses else None
        assert all(e.pose is None for e in s.episode.estimates[: first_tracking or None])
        if textured:
            assert s.outcome.grade == "correct"
            assert s.localizer.last_decision is not None
        else:
            assert s.outcome.grade == "undetermined"
            assert s.episode.final.status is Status.AMBIGUOUS
        a = run_plain_amcl(scen, start, np.random.default_rng(2), duration=5.0)
        assert a.outcome.grade in ("correct", "confident_wrong", "undetermined")
    finally:
        scen.close()
