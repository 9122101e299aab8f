"""The node's path and the bench's path build the same localizer: identical estimates.

One bench trial (a square room, realistic sensors, a global start) runs through the bench's
own loop (:func:`symloc.bench.trial.run_trial`), which records every scan, odometry reading
and image it hands the localizer and every estimate it gets back. The same inputs are then
played into :class:`symloc.ros.core.NodeCore` as the node receives them, with the bench
scenario's settings translated into ROS parameter values and back
(:func:`symloc.ros.nav2_params.settings_to_ros`, :func:`node_params_from_ros`): every scan
must give the same status, pose, covariance and reason, bit for bit.

The one liberty taken with the bench: its trial draws AMCL's random numbers from the generator
that also draws the sensor noise; here AMCL gets ``default_rng(SEED)`` of its own, which is
what the node gives it (``seed``), so that the two runs can see the same random numbers.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from symloc.bench.scenario import build_scenario
from symloc.bench.trial import TrialConfig, TrialSpec, run_trial
from symloc.bench.world_sources import WorldRef, build_world
from symloc.localizer import Estimate
from symloc.odometry import OdometryReading
from symloc.ros.assemble import make_localizer
from symloc.ros.core import NodeCore
from symloc.ros.nav2_params import node_params_from_ros, settings_to_ros

SEED = 5


class Recorder:
    """A localizer that records what it is given and what it answers."""

    def __init__(self, loc: Any) -> None:
        self.loc = loc
        self.steps: list[tuple[OdometryReading, Any, Any, Estimate]] = []
        self.starts: list[str] = []

    def reset_global(self) -> None:
        self.starts.append("global")
        self.loc.reset_global()

    def set_pose(self, pose: Any, cov: Any) -> None:
        self.starts.append("pose")
        self.loc.set_pose(pose, cov)

    def update(self, odom: OdometryReading, scan: Any, image: Any = None) -> Estimate:
        est = self.loc.update(odom, scan, image)
        self.steps.append((odom, scan, image, est))
        return est

    def __getattr__(self, name: str) -> Any:
        return getattr(self.loc, name)


def _same(a: Any, b: Any) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return bool(np.array_equal(np.asarray(a), np.asarray(b)))


@pytest.mark.slow
def test_a_bench_trial_through_the_node_gives_identical_estimates(tmp_path: Path) -> None:
    room = build_world(WorldRef("builtin", "square", 0))
    scen = build_scenario(room, rng=0, workdir=tmp_path, map_source="raster", regime="realistic")
    build = scen.localizer
    recorders: list[Recorder] = []

    def recording(rng: np.random.Generator, config: Any = None) -> Recorder:
        recorders.append(Recorder(build(np.random.default_rng(SEED), config)))
        return recorders[-1]

    scen.localizer = recording  # type: ignore[method-assign]
    spec = TrialSpec("square#0", "square", 0, "global", 3)
    run_trial(scen, spec, TrialConfig(claim_timeout=40.0, track_time=3.0), methods=("symloc",))
    (bench,) = recorders
    assert bench.starts == ["global"]
    steps = bench.steps
    assert 50 <= len(steps) <= 400
    statuses = {est.status.value for *_, est in steps}
    # the trial went through the symmetric room's phases, an image decision and tracking
    assert {"ambiguous", "deciding", "tracking"} <= statuses, statuses
    assert any(image is not None for _, _, image, _ in steps)

    # the node: the scenario's settings as ROS parameters, read back as the node reads them
    settings = dataclasses.replace(scen.settings, seed=SEED)
    values = settings_to_ros(settings, laser_pose_source="parameters", odom_source="topic")
    params = node_params_from_ros(values)
    assert params.settings() == settings
    core = NodeCore(params, factory=lambda grid, p: make_localizer(grid, p, places=scen.store))
    assert core.set_map(scen.grid)
    for k, (odom, scan, image, want) in enumerate(steps):
        core.add_odometry(odom)
        if image is not None:  # the camera answers the capture request before the next scan
            core.add_image(image, scan.stamp)
        out = core.add_scan(scan)
        assert out.used, (k, out.status)
        got = out.estimate
        assert got.status is want.status, (k, got.reason, want.reason)
        assert got.reason == want.reason, k
        assert _same(got.pose, want.pose), k
        assert _same(got.covariance, want.covariance), k
        assert (got.request is None) == (want.request is None), k
        if got.request is not None and want.request is not None:
            assert got.request.kind is want.request.kind, k
            assert _same(got.request.target, want.request.target), k
            assert got.request.angle == want.request.angle, k
    assert core.dropped == {}
