"""The node never gets stuck: each state that used to leave it localizing nothing recovers
within 5 scans, and every scan gets a status.

A robot circles in an L-shaped room (asymmetric, so AMCL tracks) with the real localizer
(500 particles), seeded with its true pose; after 10 good scans one fault is injected, then
20 more scans follow. Before the fix these states answered 0 of the next 20 scans or tracked a
wrong pose for good (issue 15).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from symloc.geometry import compose
from symloc.grid import OccupancyGrid
from symloc.mcl.params import AmclParams
from symloc.msgs import (
    build_rosbags,
    grid_to_fields,
    odometry_to_fields,
    pose_with_covariance_to_fields,
    scan_to_fields,
)
from symloc.odometry import OdometryReading
from symloc.ros.core import NodeCore, Outputs
from symloc.ros.params import NodeParams
from symloc.sim.lidar import PRESETS, simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import build_room

TS = get_typestore(Stores.ROS2_HUMBLE)
T0 = 2000.0  # the clock can jump back 1000 s
RECOVER_WITHIN = 5


@dataclass
class Run:
    """A circling robot and the node; ``step`` sends one odometry and one scan."""

    room: object
    grid: OccupancyGrid
    core: NodeCore
    rng: np.random.Generator
    t: float = T0
    clock_offset: float = 0.0
    odom_fix: np.ndarray | None = None
    preset: str = "lds01"
    outputs: list[Outputs] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def truth(self, t: float) -> np.ndarray:
        c = np.asarray(self.room.center, float)  # type: ignore[attr-defined]
        a = 0.5 * (t - T0)
        return np.array(
            [c[0] + 0.3 * math.cos(a), c[1] + 0.3 * math.sin(a), math.remainder(a + 1.57, 6.2832)]
        )

    def odom(self, t: float, pose: np.ndarray | None = None, stamp: float | None = None) -> object:
        p = self.truth(t) if pose is None else pose
        if pose is None and self.odom_fix is not None:
            p = compose(self.odom_fix, p)
        s = t + self.clock_offset if stamp is None else stamp
        f = odometry_to_fields(OdometryReading(np.asarray(p, float), s))
        return build_rosbags(TS, "nav_msgs/msg/Odometry", f)

    def scan(self, t: float, stamp: float | None = None) -> object:
        s = t + self.clock_offset if stamp is None else stamp
        sc = simulate_scan(
            self.room.world,  # type: ignore[attr-defined]
            self.truth(t),
            PRESETS[self.preset],
            self.rng,
            stamp=s,
            frame_id="laser",
        )
        return build_rosbags(TS, "sensor_msgs/msg/LaserScan", scan_to_fields(sc))

    def step(self) -> Outputs:
        self.t += 0.1
        self.core.on_odom(self.odom(self.t))
        out = self.core.on_scan(self.scan(self.t))
        self.outputs.append(out)
        return out

    def correct(self, out: Outputs) -> bool:
        est = out.estimate
        return (
            out.used
            and est.status.value == "tracking"
            and est.pose is not None
            and float(np.hypot(*(est.pose[:2] - self.truth(self.t)[:2]))) < 0.2
        )


def initialpose(pose: object, cov: np.ndarray) -> object:
    f = pose_with_covariance_to_fields(pose, cov, stamp=0.0)
    return build_rosbags(TS, "geometry_msgs/msg/PoseWithCovarianceStamped", f)


def map_msg(grid: OccupancyGrid) -> object:
    return build_rosbags(TS, "nav_msgs/msg/OccupancyGrid", grid_to_fields(grid, stamp=0.0))


@pytest.fixture(scope="module")
def world() -> tuple[object, OccupancyGrid]:
    room = build_room("l_shaped", 2.0, lab=False)
    return room, world_to_grid(room.world, 0.05)


def _start(world: tuple[object, OccupancyGrid], before_map: Callable[[NodeCore], None]) -> Run:
    room, grid = world
    params = NodeParams(amcl=AmclParams(max_particles=500, min_particles=100))
    warnings: list[str] = []
    core = NodeCore(params, warn=warnings.append)
    run = Run(room, grid, core, np.random.default_rng(0), warnings=warnings)
    before_map(core)
    core.on_map(map_msg(grid))
    core.on_odom(run.odom(run.t))
    core.on_initialpose(initialpose(run.truth(run.t), np.diag([0.01, 0.01, 0.01])))
    for _ in range(10):
        assert run.correct(run.step())
    return run


def _future_odom(dt: float) -> Callable[[Run], None]:
    def inject(run: Run) -> None:
        run.core.on_odom(run.odom(run.t, stamp=run.t + dt))

    return inject


def _scan_and_odom_jump(run: Run) -> None:
    run.core.on_odom(run.odom(run.t, stamp=run.t + 1e6))
    run.core.on_scan(run.scan(run.t, stamp=run.t + 1e6))


def _small_scan_and_odom_jump(run: Run) -> None:
    run.core.on_odom(run.odom(run.t, stamp=run.t + 3.0))
    run.core.on_scan(run.scan(run.t, stamp=run.t + 3.0))


def _clock(offset: float) -> Callable[[Run], None]:
    def inject(run: Run) -> None:
        run.clock_offset = offset

    return inject


def _absurd_odom(value: float) -> Callable[[Run], None]:
    def inject(run: Run) -> None:
        run.t += 0.1
        run.core.on_odom(run.odom(run.t, pose=np.array([value, value, 0.0])))
        run.outputs.append(run.core.on_scan(run.scan(run.t)))

    return inject


def _odom_leap(run: Run) -> None:
    run.core.on_odom(run.odom(run.t + 0.05, pose=np.array([1e5, 0.0, 0.0])))


def _odom_reset(run: Run) -> None:
    run.odom_fix = np.array([50.0, -20.0, 1.0])


def _initialpose(pose: list[float], cov: np.ndarray) -> Callable[[Run], None]:
    def inject(run: Run) -> None:
        run.core.on_initialpose(initialpose(pose, cov))

    return inject


def _initialpose_cov(run: Run) -> None:
    run.core.on_initialpose(initialpose(run.truth(run.t), np.eye(3) * 1e300))


FAULTS: dict[str, Callable[[Run], None]] = {
    "odometry 20 s in the future": _future_odom(20.0),
    "odometry 1e6 s in the future": _future_odom(1e6),
    "odometry 3 s in the future": _future_odom(3.0),
    "scan + odometry stamped 1e6 s ahead once": _scan_and_odom_jump,
    "scan + odometry stamped 3 s ahead once": _small_scan_and_odom_jump,
    "clock jumps back 1000 s for good": _clock(-1000.0),
    "clock jumps ahead 1000 s for good": _clock(1000.0),
    "odometry at 1e154 m": _absurd_odom(1e154),
    "odometry at 1e300 m": _absurd_odom(1e300),
    "odometry leaps 1e5 m once": _odom_leap,
    "odometry resets (jumps 54 m for good)": _odom_reset,
    "initialpose at 1e154 m": _initialpose([1e154, 0.0, 0.0], np.eye(3) * 0.1),
    "initialpose at 1e300 m": _initialpose([1e300, 1e300, 0.0], np.eye(3) * 0.1),
    "initialpose with covariance 1e300": _initialpose_cov,
}


@pytest.mark.parametrize("fault", list(FAULTS))
def test_recovers_within_five_scans(world: tuple[object, OccupancyGrid], fault: str) -> None:
    run = _start(world, lambda core: None)
    FAULTS[fault](run)
    n0 = len(run.outputs)
    for _ in range(20):
        run.step()
    after = run.outputs[n0:]
    ok = [o.used and o.estimate.status.value == "tracking" for o in after]
    assert True in ok, f"{fault}: never recovered: {ok}"
    first = ok.index(True)
    assert first < RECOVER_WITHIN, f"{fault}: {ok}"
    assert all(ok[first:]), f"{fault}: lost again after recovering: {ok}"
    assert run.correct(after[-1])
    # a status for every scan, used or not
    assert all(o.status["status"][0]["values"] for o in run.outputs)
    assert sum(run.core.dropped.values()) + sum(run.core.recovered.values()) >= 1


def test_unusable_first_map_is_not_stored(world: tuple[object, OccupancyGrid]) -> None:
    walls = OccupancyGrid(np.full((20, 20), 100, np.int8), 0.05)
    run = _start(world, lambda core: core.on_map(map_msg(walls)))
    assert run.core.dropped["map: unusable"] == 1
    assert any("map: unusable" in w and "no free cell" in w for w in run.warnings)
    assert run.core.grid is not None
    assert run.core.grid.width == run.grid.width
    assert "map: changed" not in run.core.dropped


def test_dropped_scans_still_get_a_status_and_go_stale(world: tuple[object, OccupancyGrid]) -> None:
    run = _start(world, lambda core: None)
    statuses = []
    for i in range(7):  # scans with no odometry near them (odometry stopped)
        run.t += 1.5
        out = run.core.on_scan(run.scan(run.t))
        assert not out.used
        assert out.amcl_pose is None
        assert out.goal is None
        values = {kv["key"]: kv["value"] for kv in out.status["status"][0]["values"]}
        assert values["scan"] == "dropped"
        assert values["reason"].startswith("scan not used (scan: ")
        if i == 0:
            assert "no odometry within transform_tolerance" in values["reason"]
        statuses.append(values["status"])
    # the last status while fewer than STALE_SCANS were lost, then "lost"
    assert statuses[:4] == ["tracking"] * 4
    assert statuses[4:] == ["lost"] * 3


def test_localizer_that_keeps_failing_is_rebuilt(world: tuple[object, OccupancyGrid]) -> None:
    run = _start(world, lambda core: None)
    broken = run.core.localizer

    def fail(*args: object, **kwargs: object) -> None:
        raise FloatingPointError("covariance is not positive definite")

    broken.update = fail
    outs = [run.step() for _ in range(5)]
    assert [o.used for o in outs[:3]] == [False] * 3
    assert run.core.localizer is not broken
    assert run.core.recovered["localizer"] == 1
    assert outs[3].used  # the rebuilt localizer answers (globally initialised)


# ---------------------------------------------------------------- first messages (issue 31)


def _odd_scan(run: Run, n: int) -> object:
    """A scan of ``n`` beams at the robot's pose: the simulated scan cut to its first ``n``
    beams (n < 360), or resampled to ``n`` beams over the full circle (n > 360)."""
    base = simulate_scan(
        run.room.world,  # type: ignore[attr-defined]
        run.truth(run.t),
        PRESETS["lds01"],
        run.rng,
        stamp=run.t + run.clock_offset,
        frame_id="laser",
    )
    f = scan_to_fields(base)
    f["intensities"] = np.zeros(0, np.float32)
    if n > len(base):
        around = np.r_[base.ranges, base.ranges[0]]
        f["ranges"] = np.interp(
            np.linspace(0, len(base), n, endpoint=False), np.arange(len(around)), around
        ).astype(np.float32)
        f["angle_increment"] = float(base.angle_increment) * len(base) / n
        f["angle_max"] = f["angle_min"] + f["angle_increment"] * (n - 1)
    else:
        f["ranges"] = np.asarray(f["ranges"])[:n]
    return build_rosbags(TS, "sensor_msgs/msg/LaserScan", f)


def _params(**changes: object) -> NodeParams:
    return NodeParams(amcl=AmclParams(max_particles=500, min_particles=100), **changes)  # type: ignore[arg-type]


def _tracks_within(run: Run, scans: int, within: int) -> list[bool]:
    outs = [run.step() for _ in range(scans)]
    ok = [run.correct(o) for o in outs]
    assert True in ok, f"never tracked: {ok}"
    first = ok.index(True)
    assert first < within, ok
    assert all(ok[first:]), f"lost again: {ok}"
    return ok


@pytest.mark.parametrize("beams", [1, 7, 359, 800, 65536])
def test_an_odd_first_scan_does_not_fix_the_beam_count(
    world: tuple[object, OccupancyGrid], beams: int
) -> None:
    """The first scan used has another length than all later ones: the later ones become the
    beam count after CONFIRM scans (issue 31: they were dropped as `scan: wrong length`
    forever)."""
    room, grid = world
    warnings: list[str] = []
    core = NodeCore(_params(), warn=warnings.append)
    run = Run(room, grid, core, np.random.default_rng(0), warnings=warnings)
    core.on_map(map_msg(grid))
    core.on_odom(run.odom(run.t))
    core.on_initialpose(initialpose(run.truth(run.t), np.diag([0.01, 0.01, 0.01])))
    run.t += 0.1
    core.on_odom(run.odom(run.t))
    core.on_scan(_odd_scan(run, beams))
    ok = _tracks_within(run, 15, RECOVER_WITHIN)
    if core.dropped["scan: wrong length"]:  # the odd scan was used: the good ones re-took
        assert core.recovered["beam count"] == 1
        assert any("beam count is now 360" in w for w in warnings)
        # the status of a dropped scan said how the beam count changes
        why = run.outputs[0].status["status"][0]["values"]
        reason = {kv["key"]: kv["value"] for kv in why}["reason"]
        assert f"360 beams, expected {beams}" in reason
        assert "of 3 scans in a row" in reason
    print(f"{beams} beams first: tracking from good scan {ok.index(True) + 1}")


def test_a_new_laser_for_good_is_taken_within_a_few_scans(
    world: tuple[object, OccupancyGrid],
) -> None:
    """The laser driver restarts with another resolution (360 -> 800 beams): tracking goes
    on after CONFIRM scans, the pose kept."""
    run = _start(world, lambda core: None)
    run.preset = "rplidar_a2"
    _tracks_within(run, 12, RECOVER_WITHIN)
    assert run.core.recovered["beam count"] == 1
    assert run.core.dropped["scan: wrong length"] == 2


def test_one_short_scan_is_dropped_and_does_not_change_the_beam_count(
    world: tuple[object, OccupancyGrid],
) -> None:
    run = _start(world, lambda core: None)
    run.t += 0.1
    run.core.on_odom(run.odom(run.t))
    assert not run.core.on_scan(_odd_scan(run, 300)).used
    _tracks_within(run, 5, 1)
    assert run.core.dropped["scan: wrong length"] == 1
    assert run.core.recovered["beam count"] == 0


DEGENERATE = {
    "1 x 1 free": np.zeros((1, 1), np.int8),
    "1 x 1 wall": np.full((1, 1), 100, np.int8),
    "3 x 3 free": np.zeros((3, 3), np.int8),
    "3 x 3 unknown": np.full((3, 3), -1, np.int8),
    "80 x 80 without walls": np.zeros((80, 80), np.int8),
}


@pytest.mark.parametrize("first_map_only", [False, True])
@pytest.mark.parametrize("shape", list(DEGENERATE))
def test_a_degenerate_first_map_gives_way_to_a_good_one(
    world: tuple[object, OccupancyGrid], shape: str, first_map_only: bool
) -> None:
    """A 1 x 1, 3 x 3 or wall-less first map is refused (nothing a scan could match), the
    scans say why, and the good map that follows is used, even with first_map_only."""
    room, grid = world
    warnings: list[str] = []
    core = NodeCore(_params(first_map_only=first_map_only), warn=warnings.append)
    run = Run(room, grid, core, np.random.default_rng(0), warnings=warnings)
    core.on_map(map_msg(OccupancyGrid(DEGENERATE[shape], 0.05)))
    assert core.grid is None
    assert core.dropped["map: unusable"] == 1
    out = run.step()
    reason = {kv["key"]: kv["value"] for kv in out.status["status"][0]["values"]}["reason"]
    assert not out.used
    assert "the last map was refused" in reason, reason
    core.on_map(map_msg(grid))
    assert core.grid is not None
    assert core.grid.width == grid.width
    core.on_initialpose(initialpose(run.truth(run.t), np.diag([0.01, 0.01, 0.01])))
    _tracks_within(run, 8, 2)
