"""An axis family whose ends the scan sees is one pose per heading class
(symloc.localizer.axis_pin); a corridor whose ends are out of range stays an axis."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from symloc.geometry import wrap_angle
from symloc.grid.fields import surface_distance_field
from symloc.localizer import LocalizerConfig
from symloc.localizer.axis_pin import PIN_GAIN, pin_axis
from symloc.localizer.claim import WALLS_MATCH, ClaimGate
from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import hallway

ALPHAS = (0.05, 0.05, 0.05, 0.05)


def _setting(length: float, truth: np.ndarray, seed: int = 0):  # type: ignore[no-untyped-def]
    """A ``length`` x 2 m corridor along x centred at the origin, a claim gate on its map, the
    scan from ``truth``, and what the global search lists there: poses all along both heading
    classes' lines (the forward one through the truth, the half-turned one mirrored about
    the corridor's centre line)."""
    room = hallway(length, 2.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    gate = ClaimGate(surface_distance_field(grid), ALPHAS, match_config=WALLS_MATCH)
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, seed)
    c = np.asarray(room.center, dtype=np.float64)
    xs = c[0] + np.linspace(-0.3, 0.3, 7) * length
    forward = np.column_stack([xs, np.full(7, truth[1]), np.full(7, truth[2])])
    mirrored = 2.0 * c[1] - truth[1]
    back = np.column_stack(
        [xs, np.full(7, mirrored), np.full(7, float(wrap_angle(truth[2] + math.pi)))]
    )
    poses = np.column_stack([forward, back]).reshape(-1, 3)
    config = LocalizerConfig(decide_here=True, axis_pin_gain=PIN_GAIN)
    ctx = SimpleNamespace(config=config, gate=gate, grid=grid)
    return ctx, SimpleNamespace(scan=scan), poses, c


def test_a_short_corridors_ends_pin_one_pose_per_heading_class() -> None:
    """15 m long, both ends within the lidar's 16 m: the forward class is pinned at the truth,
    the half-turned one at the truth's copy turned about the corridor's centre."""
    probe = hallway(15.0, 2.0)
    c = np.asarray(probe.center, dtype=np.float64)
    truth = np.array([c[0] + 3.2, c[1] + 0.3, 0.05])
    ctx, inp, poses, c = _setting(15.0, truth)
    found = pin_axis(ctx, inp, poses)  # type: ignore[arg-type]
    assert found is not None
    pinned, fits = found
    assert pinned.shape == (2, 3)
    assert fits.shape == (2,)
    assert np.all(fits >= ctx.config.decide_min_fit)
    copy = np.array([2 * c[0] - truth[0], 2 * c[1] - truth[1], truth[2] + math.pi])
    for want in (truth, copy):
        near = [
            math.hypot(*(p[:2] - want[:2])) < 0.05
            and abs(float(wrap_angle(p[2] - want[2]))) < math.radians(1.0)
            for p in pinned
        ]
        assert sum(near) == 1


def test_a_long_corridors_axis_is_not_pinned() -> None:
    """60 m long, the robot near the middle: no end in the lidar's range, no pose better than
    any other along the line."""
    probe = hallway(60.0, 2.0)
    c = np.asarray(probe.center, dtype=np.float64)
    ctx, inp, poses, _ = _setting(60.0, np.array([c[0] + 2.0, c[1] + 0.3, 0.05]))
    assert pin_axis(ctx, inp, poses) is None  # type: ignore[arg-type]


def test_only_a_corridor_mapped_with_an_end_in_view_is_pinned() -> None:
    """40 m long, the robot 9 m from one end: that end pins the scan, but a mapping trip along
    this corridor drove a stretch with neither end in the lidar's 16 m (it is longer than
    twice the reach), where SLAM's map is off along the axis by what odometry drifted: not
    pinned. The same scan declared from a lidar that reaches 25 m is pinned, at the truth."""
    probe = hallway(40.0, 2.0)
    c = np.asarray(probe.center, dtype=np.float64)
    truth = np.array([c[0] + 11.0, c[1] + 0.3, 0.05])
    ctx, inp, poses, c = _setting(40.0, truth)
    assert pin_axis(ctx, inp, poses) is None  # type: ignore[arg-type]
    farther = SimpleNamespace(scan=dataclasses.replace(inp.scan, range_max=25.0))
    found = pin_axis(ctx, farther, poses)  # type: ignore[arg-type]
    assert found is not None
    assert min(math.hypot(*(p[:2] - truth[:2])) for p in found[0]) < 0.05


def test_the_pin_asks_for_a_clear_best_fit() -> None:
    """The same short corridor with the gain asked beyond what one end wall gives: not pinned;
    and poses that are no axis family are left alone."""
    probe = hallway(15.0, 2.0)
    c = np.asarray(probe.center, dtype=np.float64)
    ctx, inp, poses, _ = _setting(15.0, np.array([c[0] + 3.2, c[1] + 0.3, 0.05]))
    strict = SimpleNamespace(
        config=dataclasses.replace(ctx.config, axis_pin_gain=0.999), gate=ctx.gate, grid=ctx.grid
    )
    assert pin_axis(strict, inp, poses) is None  # type: ignore[arg-type]
    assert pin_axis(ctx, inp, poses[:1]) is None  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("name", "value"),
    [("axis_pin_step", 0.0), ("axis_pin_apart", -1.0), ("axis_pin_gain", 1.5)],
)
def test_pin_settings_are_validated(name: str, value: float) -> None:
    with pytest.raises(ValueError, match=name):
        LocalizerConfig(**{name: value})


def test_the_gates_walls_model_gives_way_along_a_stretch_mapped_on_odometry() -> None:
    """The claim gate's walls model gives way to ``information_scale`` along a free stretch
    longer than twice the lidar's range (mapped there on odometry along it): in a 40 m
    corridor the match's information along the axis is then the plain matcher's; declared
    from a 25 m lidar, the walls model's (larger: the end wall's beams count nearly in full)."""
    from symloc.localizer.claim import GATE_MATCH

    probe = hallway(40.0, 2.0)
    c = np.asarray(probe.center, dtype=np.float64)
    truth = np.array([c[0] + 11.0, c[1] + 0.3, 0.05])
    ctx, inp, _, _ = _setting(40.0, truth)
    gate = ctx.gate
    plain = ClaimGate(gate.field, ALPHAS, match_config=GATE_MATCH)
    pts = gate.points(inp.scan)
    prior = (truth, np.diag([0.3**2, 0.3**2, math.radians(3.0) ** 2]))
    walls_off = plain._match(pts, truth, prior, inp.scan.range_max)
    here = gate._match(pts, truth, prior, inp.scan.range_max)
    assert here.information[0, 0] == pytest.approx(walls_off.information[0, 0])
    farther = gate._match(pts, truth, prior, 25.0)
    assert farther.information[0, 0] > 2.0 * walls_off.information[0, 0]
    # the walls model fuses its pose with the prior by its own information: within a millimetre
    np.testing.assert_allclose(farther.pose, here.pose, atol=1e-3)


def test_the_pin_and_the_walls_model_are_on_by_default() -> None:
    """Both are the defaults (README, "The heavy dev lies, traced"): the default config pins
    where the ends are in view and a gain of 1 pins nothing; the default gate counts a wall's
    end points as sharing its error."""
    probe = hallway(15.0, 2.0)
    c = np.asarray(probe.center, dtype=np.float64)
    ctx, inp, poses, _ = _setting(15.0, np.array([c[0] + 3.2, c[1] + 0.3, 0.05]))
    default = SimpleNamespace(
        config=LocalizerConfig(decide_here=True), gate=ctx.gate, grid=ctx.grid
    )
    off = SimpleNamespace(
        config=LocalizerConfig(decide_here=True, axis_pin_gain=1.0), gate=ctx.gate, grid=ctx.grid
    )
    assert LocalizerConfig().axis_pin_gain == PIN_GAIN
    assert pin_axis(default, inp, poses) is not None  # type: ignore[arg-type]
    assert pin_axis(off, inp, poses) is None  # type: ignore[arg-type]
    plain = ClaimGate(ctx.gate.field, ALPHAS).match_config
    assert plain is WALLS_MATCH
    assert plain.wall_std > 0.0
    assert plain.wall_tilt_std > 0.0
