"""Where to look: the turn in place that shows the camera keyframes for the most hypotheses.

The camera can only verify a hypothesis where the visual map holds keyframes that a camera at
that pose should be seeing (:func:`symloc.vision.verification.expected_keyframes`: taken
nearby, looking a similar way). A keyframe map recorded along a mapping trip looks mostly
along the walls, so an image taken at a random heading often has nothing to be compared with,
for any hypothesis, and a fixed turn between views finds such a heading only by chance.

:func:`plan_turn` asks the keyframe store instead: for every candidate turn (multiples of
``step`` over the full circle), how many hypotheses, turned by it in place, predict at least
one keyframe, and how many keyframes in all (each hypothesis' count capped, so that one
hypothesis near many keyframes does not outweigh two near a few). The best turn wins, the
smallest one among equals; headings the camera has already seen (within ``spacing`` of them)
are not candidates. A plan whose best turn covers no hypothesis says that no image will
decide here. A turn stops within some ``margin`` of where it was sent (the localizer's
``decide_turn_tolerance``), and a hypothesis sees a keyframe only within 40 deg of the
keyframe's heading: so a turn first counts the hypotheses still covered ``margin`` short of
it and beyond it, and a heading in the middle of where they are covered beats one at its
edge, which the robot would stop short of and then turn again.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import wrap_angle

__all__ = ["ViewPlan", "plan_turn"]

FloatArray = NDArray[np.float64]
#: Poses (P, 3) -> how many keyframes a camera at each pose should be seeing, (P,) ints.
ExpectedCounts = Callable[[FloatArray], NDArray[np.int64]]

#: A hypothesis' expected keyframes count towards a plan's score up to this many.
COUNT_CAP = 3


@dataclass(frozen=True)
class ViewPlan:
    """:func:`plan_turn`'s answer: ``turn`` [rad] (counter-clockwise positive; 0: look
    here), ``covered`` how many hypotheses then expect a keyframe, ``expected`` how many
    keyframes they expect in all (each capped at :data:`COUNT_CAP`)."""

    turn: float
    covered: int
    expected: int

    @property
    def useful(self) -> bool:
        """Whether an image after this turn can verify anything."""
        return self.covered > 0


def plan_turn(
    poses: FloatArray,
    expected_counts: ExpectedCounts,
    *,
    seen: Sequence[float] = (),
    step: float = math.radians(30.0),
    spacing: float = math.radians(45.0),
    margin: float = 0.0,
) -> ViewPlan:
    """The turn in place after which an image can verify the most hypotheses.

    Parameters
    ----------
    poses : (K, 3) array
        The hypotheses now (map frame; x [m], y [m], theta [rad]).
    expected_counts : callable
        Poses ``(P, 3)`` -> keyframes each should see ``(P,)``
        (:meth:`symloc.localizer.types.KeyframeStore.expected_counts`).
    seen : sequence of float
        Turns [rad] from the current heading at which images were already taken.
    step : float
        Spacing [rad] of the candidate turns over the full circle, in (0, pi].
    spacing : float
        A candidate within this angle [rad] of a heading in ``seen`` is skipped.
    margin : float
        How far [rad] short of or beyond a turn the robot may stop: candidates are ranked
        first by the hypotheses covered at all of ``turn - margin``, ``turn`` and
        ``turn + margin`` (0: at ``turn`` only).

    Returns
    -------
    ViewPlan
        The best candidate (ties: the smallest turn); ``covered == 0`` when none helps.
    """
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    n = max(1, round(2.0 * math.pi / step))
    turns = np.asarray(wrap_angle(2.0 * math.pi * np.arange(n) / n), dtype=np.float64)
    if len(seen):
        gap = np.abs(np.asarray(wrap_angle(turns[:, None] - np.asarray(seen, np.float64)[None, :])))
        turns = turns[(gap > spacing).all(axis=1)]
    if p.shape[0] == 0 or turns.size == 0:
        return ViewPlan(0.0, 0, 0)
    offsets = np.array([0.0, -margin, margin]) if margin > 0.0 else np.zeros(1)
    turned = np.broadcast_to(p, (offsets.size, turns.size, *p.shape)).copy()  # (O, M, K, 3)
    turned[..., 2] = wrap_angle(turned[..., 2] + (offsets[:, None] + turns[None, :])[..., None])
    counts = np.asarray(expected_counts(turned.reshape(-1, 3)), dtype=np.int64)
    counts = counts.reshape(offsets.size, turns.size, p.shape[0])
    covered = (counts[0] > 0).sum(axis=1)
    robust = (counts > 0).all(axis=0).sum(axis=1)
    expected = np.minimum(counts[0], COUNT_CAP).sum(axis=1)
    # lexicographic: hypotheses covered wherever the turn stops, then covered where it was
    # sent, then keyframes expected, then the smallest turn
    key = np.lexsort((np.abs(turns), -expected, -covered, -robust))
    best = int(key[0])
    return ViewPlan(float(turns[best]), int(covered[best]), int(expected[best]))
