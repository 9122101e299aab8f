"""Rotated copies of a pose about a symmetric place, and whether they explain a scan as well.

A pose inside a place of rotational order ``k`` has ``k - 1`` rotated copies that see the same
room; AMCL may hold several of them (:func:`symmetry_consistent`) or collapse onto one. Before
the localizer first publishes a pose it asks whether a copy fits the scan about as well
(:func:`copies_verdict`, :func:`copies_fit`): then the pose is not earned.

"About as well" (:class:`CopyRule`) is first relative: the copy's score is at least ``ratio``
x the pose's. But the pose can fit clearly better than its true copy: a SLAM map a few
centimetres to decimetres off near a wall costs the truth the beams on that wall (they end
beyond the match's 10 cm), and a wrong copy whose view misses that wall then fits better (a
T-shaped room: the truth 80 % of beams, the wrong end of the bar 94 %). With the claim gate's
aligned fits two more tests keep such a copy open:

- *slack*: the shares of beams within ``slack`` [m] of the walls (a map error's size, not a
  scan's noise) are compared by the same ratio. A map error moves the truth's beams by
  centimetres to decimetres, inside the slack; what tells a wrong copy apart (furniture it
  does not see, a wing of the room where its map has a wall) moves them by metres.
- *claim floor*: a copy whose aligned fit reaches the gate's ``min_claim_fit`` is a pose the
  gate itself would claim, whatever the pose's own fit. The strictest test: in a nearly
  symmetric room (furniture, a wing of an L) most copies fit that well.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.geometry import angle_diff, wrap_angle
from symloc.scan import LaserScan
from symloc.symmetry.order import SymmetryOrder

from .claim import ClaimGate
from .types import Hypothesis, Place

__all__ = [
    "CIRCLE_SAMPLES",
    "CopiesKind",
    "CopiesVerdict",
    "CopyRule",
    "CopyScores",
    "PoseScorer",
    "claim_floor",
    "copies_fit",
    "copies_verdict",
    "known_place_at",
    "rotated_copies",
    "symmetry_consistent",
]

FloatArray = NDArray[np.float64]
#: Poses x scan -> (K,) scores in [0, 1]: how well the scan fits the map at each pose.
PoseScorer = Callable[[FloatArray, Any], FloatArray]

#: How many candidates to list for a circle (infinite order).
CIRCLE_SAMPLES = 8


def rotated_copies(pose: FloatArray, center: FloatArray, order: SymmetryOrder) -> FloatArray:
    """The ``k`` poses ``(k, 3)`` obtained by rotating ``pose`` (3,) about ``center`` (2,).

    A circle gives :data:`CIRCLE_SAMPLES` evenly spaced copies. Copy 0 is ``pose``.
    """
    if not isinstance(order, SymmetryOrder):
        raise ConfigurationError(f"rotated_copies: expected a SymmetryOrder, got {order!r}")
    k = order.copies(CIRCLE_SAMPLES)
    phi = 2.0 * np.pi * np.arange(k) / k
    c, s = np.cos(phi), np.sin(phi)
    d = np.asarray(pose[:2], dtype=np.float64) - center
    out = np.empty((k, 3))
    out[:, 0] = center[0] + c * d[0] - s * d[1]
    out[:, 1] = center[1] + s * d[0] + c * d[1]
    out[:, 2] = wrap_angle(pose[2] + phi)
    return out


def symmetry_consistent(
    hypotheses: Sequence[Hypothesis],
    center: FloatArray,
    order: SymmetryOrder,
    *,
    min_weight: float,
    position_tol: float,
    angle_tol: float,
) -> int:
    """How many well-weighted clusters are symmetric images of the heaviest one.

    Counts the heaviest cluster itself, so a value >= 2 means AMCL's hypotheses are related by
    the place's rotation of order ``order`` (a circle: any angle) about ``center`` (2,) [m].
    """
    strong = [h for h in hypotheses if h.weight >= min_weight]
    if not strong:
        return 0
    ref = max(strong, key=lambda h: h.weight)
    count = 1
    for h in strong:
        if h is ref:
            continue
        phi = float(angle_diff(h.pose[2], ref.pose[2]))
        step = order.step
        if step is not None:
            phi = round(phi / step) * step
            if abs(float(angle_diff(h.pose[2], ref.pose[2] + phi))) > angle_tol:
                continue
        if abs(phi) < angle_tol:
            continue  # the same heading: a split of one cluster, not a symmetric copy
        expect = rotated_copies(ref.pose, center, order)
        if step is None:
            expect = rotated_copies(ref.pose, center, SymmetryOrder.finite(1)).copy()
            c, s = math.cos(phi), math.sin(phi)
            d = ref.pose[:2] - center
            expect[0, :2] = center + np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]])
            expect[0, 2] = wrap_angle(ref.pose[2] + phi)
        dist = np.hypot(expect[:, 0] - h.pose[0], expect[:, 1] - h.pose[1])
        if float(dist.min()) <= position_tol:
            count += 1
    return count


class CopiesKind(enum.Enum):
    """How a pose's rotated copies explain a scan compared with the pose itself."""

    UNIQUE = "unique"  # every copy explains it clearly worse
    AMBIGUOUS = "ambiguous"  # some copy explains it about as well
    BETTER = "better"  # copy ``index`` explains it clearly better


@dataclass(frozen=True, slots=True)
class CopiesVerdict:
    """:func:`copies_verdict`'s answer; ``index`` is the better copy's (BETTER only)."""

    kind: CopiesKind
    index: int | None = None


@dataclass(frozen=True, slots=True)
class CopyRule:
    """When a rotated copy explains a scan about as well as the pose (see the module
    docstring): its score is at least ``ratio`` x the pose's; or, with the claim gate's
    aligned fits, ``claim_floor`` and its fit reaches the gate's ``min_claim_fit``; or
    ``slack`` [m] > 0 and its share of beams within ``slack`` of the walls (at its aligned
    pose) is at least ``ratio`` x the pose's."""

    ratio: float
    claim_floor: bool = True
    slack: float = 0.0


@dataclass(frozen=True, eq=False)
class CopyScores:
    """How well a scan fits the map at a pose and its copies (the pose first): ``fits`` (k,)
    the scores, ``loose`` (k,) the shares of beams within the rule's slack (None without a
    slack or a gate) and ``floor`` the share of beams at which a copy fits well enough for
    the claim gate to claim it (infinity when that test is off or ``fits`` are a pose
    scorer's, not shares of beams)."""

    fits: FloatArray
    loose: FloatArray | None
    floor: float

    def open(self, ratio: float) -> bool:
        """True when a copy is about as good as the pose (:class:`CopyRule`)."""
        rest = self.fits[1:]
        if np.any(rest >= ratio * max(float(self.fits[0]), 1e-12)) or np.any(rest >= self.floor):
            return True
        loose = self.loose
        return loose is not None and bool(np.any(loose[1:] >= ratio * max(float(loose[0]), 1e-12)))


def copy_scores(
    copies: FloatArray,
    scan: object,
    gate: ClaimGate | None,
    scorer: PoseScorer | None,
    rule: CopyRule | None = None,
) -> CopyScores | None:
    """How well ``scan`` fits the map at each pose ``(k, 3)``: with a claim gate, each is
    first aligned to the map (a copy about an imprecise centre is a few centimetres off)
    and scored by the share of beams that fit (and, with the ``rule``'s slack, the share
    within the slack); else the pose scorer's score; None without either."""
    if gate is not None and isinstance(scan, LaserScan):
        aligned = [gate.fit(c, scan) for c in copies]
        fits = np.array([fit for _, fit in aligned])
        loose = None
        if rule is not None and rule.slack > 0.0:
            loose = np.array([gate.share_within(p, scan, rule.slack) for p, _ in aligned])
        floor = claim_floor(scan, gate) if rule is None or rule.claim_floor else math.inf
        return CopyScores(fits, loose, floor)
    if scorer is None:
        return None
    return CopyScores(np.asarray(scorer(copies, scan), dtype=np.float64), None, math.inf)


def claim_floor(scan: object, gate: ClaimGate | None) -> float:
    """The share of beams at which a copy fits well enough for the claim gate to claim it
    (its ``min_claim_fit``) when :func:`copy_scores` reads the gate's aligned fits; infinity
    with a pose scorer only (its scores are not shares of beams)."""
    if gate is not None and isinstance(scan, LaserScan):
        return float(gate.config.min_claim_fit)
    return math.inf


def copies_verdict(
    pose: FloatArray,
    center: FloatArray,
    order: SymmetryOrder,
    scan: object,
    *,
    gate: ClaimGate | None,
    scorer: PoseScorer | None,
    ratio: float,
    floor: bool = True,
    slack: float = 0.0,
) -> CopiesVerdict:
    """How the rotated copies of ``pose`` (3,) about ``center`` (2,) explain ``scan``.

    BETTER with the index of a copy that explains it clearly better (the pose's score below
    ``ratio`` x the copy's); UNIQUE when every copy explains it clearly worse (none is about
    as good by the :class:`CopyRule` of ``ratio``, ``floor`` and ``slack`` [m]: a copy
    the gate would claim on its own, or one that a map off by up to ``slack`` near a wall
    may have cost beams, is never ruled out; see the module docstring); else AMBIGUOUS
    (also when nothing can score).
    """
    copies = rotated_copies(pose, center, order)
    rule = CopyRule(ratio, floor, slack)
    scores = copy_scores(copies, scan, gate, scorer, rule)
    if scores is None:
        return CopiesVerdict(CopiesKind.AMBIGUOUS)
    fits = scores.fits
    best = int(np.argmax(fits))
    if best != 0 and ratio * float(fits[best]) >= max(float(fits[0]), 1e-12):
        return CopiesVerdict(CopiesKind.BETTER, best)
    if scores.open(ratio):
        return CopiesVerdict(CopiesKind.AMBIGUOUS)
    return CopiesVerdict(CopiesKind.UNIQUE)


def copies_fit(
    pose: FloatArray,
    center: FloatArray,
    order: SymmetryOrder,
    scan: object,
    *,
    gate: ClaimGate | None,
    scorer: PoseScorer | None,
    ratio: float,
    floor: bool = True,
    slack: float = 0.0,
) -> bool:
    """True when a rotated copy of ``pose`` explains ``scan`` about as well as ``pose`` (as
    :func:`copies_verdict` judges it: AMBIGUOUS or BETTER), or nothing can score them."""
    rule = CopyRule(ratio, floor, slack)
    scores = copy_scores(rotated_copies(pose, center, order), scan, gate, scorer, rule)
    return scores is None or scores.open(ratio)


def known_place_at(pose: FloatArray, places: Sequence[Place], radius_factor: float) -> Place | None:
    """The nearest known place whose disc (``radius_factor`` x its G-V distance) holds
    ``pose``'s position, or None."""
    best: Place | None = None
    best_d = math.inf
    for place in places:
        d = float(np.hypot(*(pose[:2] - place.center)))
        if d <= radius_factor * place.gv_distance and d < best_d:
            best, best_d = place, d
    return best
