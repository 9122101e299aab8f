"""The claim gate's best-fit check: a claim the alignment left short of the scan's best fit
along its least certain axis is withheld (symloc.localizer.best_fit)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.grid.fields import surface_distance_field
from symloc.localizer.best_fit import (
    TURN_REACH,
    BestFitConfig,
    best_offset,
    fit_profile,
    off_best_fit,
    off_best_turn,
    turn_profile,
)
from symloc.localizer.claim import ClaimConfig, ClaimGate, Verdict
from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import hallway

ALPHAS = (0.05, 0.05, 0.05, 0.05)
TRUTH = np.array([1.0, 0.1, 0.05])


@pytest.fixture(scope="module")
def corridor():  # type: ignore[no-untyped-def]
    """An 8 x 2 m corridor, its field, and the points of a scan from TRUTH (both end walls in
    reach)."""
    room = hallway(8.0, 2.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    field = surface_distance_field(grid)
    gate = ClaimGate(field, ALPHAS)
    scan = simulate_scan(room.world, TRUTH, RPLIDAR_A2, 0)
    return field, gate, scan


def test_best_offset_refines_between_samples() -> None:
    offsets = BestFitConfig().offsets
    assert offsets[0] == pytest.approx(-0.3)
    assert offsets[-1] == pytest.approx(0.3)
    assert np.count_nonzero(offsets == 0.0) == 1
    fits = (offsets - 0.112) ** 2 + 1e-3
    at, gain = best_offset(offsets, fits)
    assert at == pytest.approx(0.112, abs=1e-9)  # exact for a parabola
    # the gain is the lowest sample's (at 0.1), not the parabola's: no extrapolated fit
    assert gain == pytest.approx(1.0 - (0.012**2 + 1e-3) / (0.112**2 + 1e-3))
    # a minimum at the edge is not extrapolated; a flat profile gains nothing
    assert best_offset(offsets, -offsets)[0] == pytest.approx(0.3)
    assert best_offset(offsets, np.ones_like(offsets)) == (pytest.approx(-0.3), 0.0)


def test_a_claim_short_of_the_scans_best_fit_along_the_corridor_is_found(corridor) -> None:  # type: ignore[no-untyped-def]
    field, gate, scan = corridor
    pts = gate.points(scan)
    along = np.diag([0.03**2, 0.01**2, 0.005**2])  # least certain along the corridor (x)
    cfg = BestFitConfig()
    assert off_best_fit(field, pts, TRUTH, along, 0.3, cfg) is None
    off = TRUTH + np.array([0.15, 0.0, 0.0])
    found = off_best_fit(field, pts, off, along, 0.3, cfg)
    assert found is not None
    offset, gain = found
    assert offset == pytest.approx(-0.15, abs=0.03)  # back to the truth
    assert gain > 0.2
    # the same profile along x matches its definition at one offset
    here = fit_profile(field, pts, off, np.array([1.0, 0.0]), np.array([0.0, -0.15]), 0.3)
    assert here[1] < here[0]
    # a claim whose own std admits the offset (3 x 6 cm > 15 cm) is not contradicted
    wide = np.diag([0.06**2, 0.01**2, 0.005**2])
    assert off_best_fit(field, pts, off, wide, 0.3, cfg) is None
    # reach 0 leaves the check out
    assert off_best_fit(field, pts, off, along, 0.3, BestFitConfig(reach=0.0)) is None


def test_the_gate_withholds_a_claim_off_the_best_fit(corridor) -> None:  # type: ignore[no-untyped-def]
    field, gate, scan = corridor
    pts = gate.points(scan)
    claim = gate.confirm(TRUTH, np.diag([0.05**2, 0.05**2, 0.02**2]), scan)
    assert claim.match is not None
    off = TRUTH + np.array([0.15, 0.0, 0.0])
    # the alignment "stopped" 15 cm along the corridor with a 2 cm std there
    stopped = dataclasses.replace(
        claim.match, pose=off, covariance=np.diag([0.02**2, 0.005**2, 0.003**2])
    )
    prior_cov = np.diag([0.1**2, 0.1**2, 0.05**2])
    judged = gate._judge(off, prior_cov, stopped, pts)
    assert judged.verdict is Verdict.WITHHELD
    assert "best fit" in judged.reason
    assert "along the pose's least certain axis" in judged.reason
    lax = ClaimGate(field, ALPHAS, ClaimConfig(best_fit_reach=0.0))
    assert lax._judge(off, prior_cov, stopped, pts).verdict is Verdict.CLAIM
    # at the truth the same match is claimed
    at_truth = dataclasses.replace(stopped, pose=TRUTH.copy())
    assert gate._judge(TRUTH, prior_cov, at_truth, pts).verdict is Verdict.CLAIM


def test_a_claim_turned_short_of_the_scans_best_fit_is_found(corridor) -> None:  # type: ignore[no-untyped-def]
    field, gate, scan = corridor
    pts = gate.points(scan)
    assert BestFitConfig().turns.size == 1  # off by default: no turn but 0
    cfg = BestFitConfig(turn_reach=TURN_REACH)
    narrow = np.diag([0.01**2, 0.01**2, math.radians(0.5) ** 2])
    profile = turn_profile(field, pts, TRUTH, cfg.turns, 0.3)
    assert abs(cfg.turns[int(np.argmin(profile))]) <= cfg.turn_step  # the truth fits best
    assert off_best_turn(field, pts, TRUTH, narrow, 0.3, cfg) is None
    turned = TRUTH + np.array([0.0, 0.0, math.radians(4.0)])
    found = off_best_turn(field, pts, turned, narrow, 0.3, cfg)
    assert found is not None
    turn, gain = found
    assert math.degrees(turn) == pytest.approx(-4.0, abs=0.5)  # back to the truth
    assert gain > 0.2
    # a heading std that admits the turn (3 x 2 deg > 4 deg), or the check left out: None
    wide = np.diag([0.01**2, 0.01**2, math.radians(2.0) ** 2])
    assert off_best_turn(field, pts, turned, wide, 0.3, cfg) is None
    assert off_best_turn(field, pts, turned, narrow, 0.3, BestFitConfig(turn_reach=0.0)) is None


def test_the_gate_withholds_a_claim_turned_off_the_best_fit(corridor) -> None:  # type: ignore[no-untyped-def]
    field, gate, scan = corridor
    pts = gate.points(scan)
    claim = gate.confirm(TRUTH, np.diag([0.05**2, 0.05**2, 0.02**2]), scan)
    assert claim.match is not None
    off = TRUTH + np.array([0.0, 0.0, math.radians(4.0)])
    # the alignment "stopped" 4 deg short with a heading std of 0.5 deg
    stopped = dataclasses.replace(
        claim.match, pose=off, covariance=np.diag([0.005**2, 0.005**2, math.radians(0.5) ** 2])
    )
    prior_cov = np.diag([0.1**2, 0.1**2, 0.1**2])
    strict = ClaimGate(field, ALPHAS, ClaimConfig(best_fit_turn_reach=TURN_REACH))
    judged = strict._judge(off, prior_cov, stopped, pts)
    assert judged.verdict is Verdict.WITHHELD
    assert "better turned" in judged.reason
    # off by default
    assert gate._judge(off, prior_cov, stopped, pts).verdict is Verdict.CLAIM


@pytest.mark.parametrize(
    ("field", "bad"),
    [
        ("reach", -0.1),
        ("step", 0.0),
        ("step", 0.5),
        ("sigmas", math.nan),
        ("gain", 1.0),
        ("turn_reach", -0.1),
        ("turn_step", 0.0),
        ("turn_floor", math.inf),
    ],
)
def test_bad_best_fit_settings_name_the_field(field: str, bad: float) -> None:
    with pytest.raises(ConfigurationError, match=f"ClaimConfig.best_fit_{field}"):
        ClaimConfig(**{f"best_fit_{field}": bad})  # type: ignore[arg-type]
