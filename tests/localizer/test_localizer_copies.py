"""Rotated copies of a pose: a copy the claim gate would claim on its own is never ruled out."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from symloc.grid import OccupancyGrid
from symloc.grid.fields import surface_distance_field
from symloc.localizer import LocalizerConfig, SymmetryVerdict, TrackerResult
from symloc.localizer.claim import ClaimConfig, ClaimGate
from symloc.localizer.context import Context, Inputs, Record
from symloc.localizer.copies import (
    CopiesKind,
    claim_floor,
    copies_fit,
    copies_verdict,
)
from symloc.localizer.decide_here import propose
from symloc.localizer.map_symmetry import MapSymmetry
from symloc.localizer.notes import Notes
from symloc.localizer.types import Hypothesis, Proposal
from symloc.mcl.beam_model import raycast_grid
from symloc.scan import LaserScan
from symloc.symmetry.order import SymmetryOrder

SCAN = LaserScan(-math.pi, 2 * math.pi / 180, 0.05, 12.0, np.full(180, 2.0))
POSE = np.array([4.0, 0.0, 0.0])  # its half-turn copy about the origin: (-4, 0, pi)
CENTRE = np.zeros(2)
HALF = SymmetryOrder.finite(2)


class FitGate:
    """A claim gate whose aligned fit (the share of beams within 10 cm) and share of beams
    within a slack are scripted by the pose's x [m]."""

    def __init__(self, fits: dict[float, float], loose: dict[float, float] | None = None):
        self.fits = fits
        self.loose = loose if loose is not None else fits
        self.config = ClaimConfig()  # min_claim_fit 0.6

    def fit(self, pose: np.ndarray, scan: LaserScan) -> tuple[np.ndarray, float]:
        return np.asarray(pose, float), self.fits.get(round(float(pose[0]), 1), 0.0)

    def share_within(self, pose: np.ndarray, scan: LaserScan, distance: float) -> float:
        return self.loose.get(round(float(pose[0]), 1), 0.0)


def _verdict(own: float, copy: float, loose=None, *, floor=True, slack=0.0):
    gate = FitGate(
        {4.0: own, -4.0: copy},
        None if loose is None else dict(zip((4.0, -4.0), loose, strict=True)),
    )
    kw = {"gate": gate, "scorer": None, "ratio": 0.9, "floor": floor, "slack": slack}
    return (
        copies_verdict(POSE, CENTRE, HALF, SCAN, **kw),
        copies_fit(POSE, CENTRE, HALF, SCAN, **kw),
    )


@pytest.mark.parametrize(
    ("own", "copy", "kind"),
    [
        # the truth fits worse than the wrong pose (the map is off near a wall), but well
        # enough for the gate to claim it: not ruled out, though below 0.9 x the pose's
        (0.94, 0.80, CopiesKind.AMBIGUOUS),
        (0.94, 0.60, CopiesKind.AMBIGUOUS),
        (0.94, 0.86, CopiesKind.AMBIGUOUS),  # the ratio alone
        (0.94, 0.55, CopiesKind.UNIQUE),
        (0.50, 0.46, CopiesKind.AMBIGUOUS),  # neither claimable: the ratio decides
        (0.50, 0.40, CopiesKind.UNIQUE),
        (0.80, 0.99, CopiesKind.BETTER),  # a copy clearly better stays BETTER
    ],
)
def test_a_copy_the_gate_would_claim_is_never_ruled_out(own, copy, kind):
    verdict, fits = _verdict(own, copy)
    assert verdict.kind is kind
    assert verdict.index == (1 if kind is CopiesKind.BETTER else None)
    assert fits is (kind is not CopiesKind.UNIQUE)


@pytest.mark.parametrize(
    ("own", "copy", "loose", "kind"),
    [
        # the truth's beams on a wall the map has 20 cm off miss by 20 cm: within the slack
        (0.94, 0.55, (0.97, 0.95), CopiesKind.AMBIGUOUS),
        # a wrong copy misses by metres (furniture it does not see, a wing of the room)
        (0.94, 0.55, (0.97, 0.60), CopiesKind.UNIQUE),
        (0.94, 0.80, (0.97, 0.80), CopiesKind.UNIQUE),  # the claim floor is off here
        (0.80, 0.99, (0.85, 0.99), CopiesKind.BETTER),
    ],
)
def test_a_copy_a_map_error_may_have_cost_beams_is_never_ruled_out(own, copy, loose, kind):
    verdict, fits = _verdict(own, copy, loose, floor=False, slack=0.3)
    assert verdict.kind is kind
    assert fits is (kind is not CopiesKind.UNIQUE)
    # without the slack (and the floor) the ratio alone rules the first one out
    assert _verdict(own, copy, loose, floor=False)[0].kind is (
        CopiesKind.BETTER if kind is CopiesKind.BETTER else CopiesKind.UNIQUE
    )


def test_share_within_counts_the_beams_a_map_error_moves():
    """A map whose right wall is 20 cm short of the room's: at the true pose the beams on that
    wall are lost to the 10 cm of the gate's fit, not to a 30 cm slack."""
    room, mapped = np.zeros((80, 140), np.int8), np.zeros((80, 140), np.int8)
    for data, right in ((room, 134), (mapped, 130)):
        data[5, 5 : right + 1] = data[74, 5 : right + 1] = data[5:75, 5] = 100
        data[5:75, right] = 100
    truth = OccupancyGrid(room, 0.05)
    pose = np.array([4.5, 2.0, 0.3])
    n = 360
    ang = -np.pi + 2 * np.pi / n * np.arange(n)
    ranges = raycast_grid(truth, np.repeat(pose[None, :2], n, 0), ang + pose[2], 12.0)
    scan = LaserScan(-np.pi, 2 * np.pi / n, 0.05, 12.0, ranges)
    gate = ClaimGate(surface_distance_field(OccupancyGrid(mapped, 0.05)))
    tight, loose = gate.share_within(pose, scan, 0.1), gate.share_within(pose, scan, 0.3)
    assert tight < 0.8
    assert loose > 0.97
    assert gate.share_within(pose + np.array([0.0, 0.0, 0.5]), scan, 0.3) < 0.5  # a wrong pose


def test_the_floor_is_the_gates_and_only_for_its_fits():
    gate = FitGate({})
    assert claim_floor(SCAN, gate) == pytest.approx(0.6)
    assert claim_floor(SCAN, None) == math.inf
    assert claim_floor(object(), gate) == math.inf  # the gate cannot read it: the scorer's

    def scorer(poses, scan):  # a score of 0.8 is not 80 % of beams: the ratio alone
        return np.array([1.0] + [0.8] * (len(poses) - 1))

    verdict = copies_verdict(POSE, CENTRE, HALF, SCAN, gate=None, scorer=scorer, ratio=0.9)
    assert verdict.kind is CopiesKind.UNIQUE
    # the floor can be turned off (LocalizerConfig.copy_claim_floor)
    assert _verdict(0.94, 0.80, floor=False)[0].kind is CopiesKind.UNIQUE


class OneProposal:
    def propose(self, scan: object) -> Proposal:
        return Proposal(POSE[None, :].copy(), np.ones(1), True)


class NoTracker:
    def initialize_global(self) -> None: ...

    def initialize_pose(self, pose, covariance) -> None: ...

    def force_update(self) -> None: ...


@pytest.mark.parametrize(
    ("copy", "loose", "floor", "survivors"),
    [
        (0.70, 0.70, True, 2),  # the claim floor keeps the copy
        (0.55, 0.55, True, 1),
        (0.70, 0.70, False, 1),
        (0.61, 0.95, False, 2),  # the slack keeps it
    ],
)
def test_deciding_here_keeps_a_copy_the_copy_check_would_not_rule_out(
    copy, loose, floor, survivors
):
    """The laser leaves one pose within its margin (0.95; the copy 0.25 or more behind), but
    the copy check that earns it would refuse it while the copy is not ruled out (it fits as
    well as the gate needs to claim, or within the map's slack): the copy survives too, for
    the camera to choose."""
    ctx = Context(
        tracker=NoTracker(),  # type: ignore[arg-type]
        places=None,  # type: ignore[arg-type]
        config=LocalizerConfig(decide_here=True, copy_claim_floor=floor),
        gate=FitGate({4.0: 0.95, -4.0: copy}, {4.0: 1.0, -4.0: loose}),  # type: ignore[arg-type]
        scorer=None,
        known_places=[],
        map_symmetries=[MapSymmetry(CENTRE, 2, 0.45, partial=True)],
        notes=Notes(logging.getLogger("test")),
        record=Record(),
        proposer=OneProposal(),
    )
    result = TrackerResult(POSE, np.eye(3) * 0.01, (Hypothesis(pose=POSE, weight=1.0),))
    verdict = SymmetryVerdict(False, SymmetryOrder.finite(1), "asymmetric", None, math.nan)
    hyp = propose(ctx, Inputs(result, verdict, SCAN, None, np.zeros(3)))
    assert hyp.complete
    assert hyp.survivors == survivors
    np.testing.assert_allclose(hyp.poses[0], POSE)
