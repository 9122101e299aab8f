"""At the centre: the G-V lookup, Algorithm 3's decision, the reseed, and mapping a new place.

The phases (:mod:`symloc.localizer.phases`) say when; these functions do the work of one image:
:func:`choose` asks every place with the visited place's G-V distance for a direction,
:func:`reseed` turns a decided direction into a pose the laser confirms and seeds AMCL there,
:func:`conclusion` says what is left when every direction was tried, and
:func:`store_mapped_place` adds a mapped place to the visual map (Algorithm 5 step 11).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from typing import cast

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import wrap_angle
from symloc.scan import LaserScan

from .claim import Verdict
from .context import Context, Inputs, Outcome, Visit, cov_from_std, people, reseed_tracker
from .directions import directions_for
from .types import Decision, DecisionStatus, Estimate, Hypothesis, Place, Status

__all__ = ["Choice", "Reseed", "Reseeded", "choose", "conclusion", "reseed", "unanchored"]


def directions(ctx: Context, visit: Visit) -> int:
    """How many directions M to try: the most of any candidate place, else the shape's own."""
    found = ctx.places.candidates(visit.gv, visit.order)
    if found:
        return max(p.m for p in found)
    return directions_for(visit.kind, visit.order)


@dataclass(frozen=True, eq=False)
class Choice:
    """:func:`choose`'s answer: the ``place`` and its ``decision``, or why to try again."""

    place: Place | None = None
    decision: Decision | None = None
    retry: str = ""


def choose(ctx: Context, visit: Visit, image: NDArray[np.uint8]) -> Choice:
    """Decide ``image`` against every place with the visit's G-V distance (nearest first).

    One place decided (or one clearly better than the others) is the choice; otherwise the
    image's :class:`Outcome` is recorded in ``visit.outcomes`` and the answer says why.
    """
    found = list(ctx.places.candidates(visit.gv, visit.order))
    if len(found) > 1:
        centre = visit.centre_map
        found.sort(key=lambda p: float(np.hypot(*(p.center - centre))))
    decisions = [(p, ctx.places.decide(p, image)) for p in found]
    decided = [(p, d) for p, d in decisions if d.status is DecisionStatus.DECIDED]
    if decided:
        if len(decided) > 1:
            decided.sort(key=lambda pd: -pd[1].score)
            if decided[1][1].score >= 0.8 * decided[0][1].score:
                visit.outcomes.append(Outcome.UNDETERMINED)
                return Choice(retry="two places decided alike")
        return Choice(*decided[0])
    if not found:
        visit.outcomes.append(Outcome.NO_PLACE)
    elif all(d.status is DecisionStatus.REFUSED for _, d in decisions):
        visit.outcomes.append(Outcome.REFUSED)
    elif all(d.status is DecisionStatus.NO_MATCH for _, d in decisions):
        visit.outcomes.append(Outcome.NO_MATCH)
    else:
        visit.outcomes.append(Outcome.UNDETERMINED)
    last = decisions[0][1].reason if decisions else "no place with this G-V distance"
    ctx.note(f"image {visit.attempt + 1}: {visit.outcomes[-1].value} ({last})")
    return Choice(retry=last)


class Reseeded(enum.Enum):
    """How a reseed at a decided pose ended."""

    REJECTED = "rejected"  # the laser contradicts the decided pose: try the next direction
    WITHHELD = "withheld"  # AMCL reseeded, the claim chain starts there, nothing published
    # until a scan confirms the pose precisely enough
    CLAIMED = "claimed"  # AMCL reseeded and the pose is published


@dataclass(frozen=True, eq=False)
class Reseed:
    """:func:`reseed`'s answer: how it ended, the estimate to publish (CLAIMED: tracking;
    WITHHELD: ambiguous, the decided pose its one hypothesis), or why."""

    outcome: Reseeded
    estimate: Estimate | None = None
    why: str = ""


def _measured_again(
    ctx: Context, inp: Inputs, pose: NDArray[np.float64]
) -> tuple[NDArray[np.float64], float] | None:
    """A round map: the laser cannot set the heading, and a place decision's is coarse
    (``decision_theta_std``). The decided pose (3,) with its heading measured again by the
    keyframes it should be seeing, and that heading's std [rad]
    (:attr:`~symloc.localizer.types.Verification.heading_std`); None without keyframes, an
    image, or a measurement, and when the localizer does not decide from where it stands
    (``LocalizerConfig.decide_here`` off: the paper's path alone)."""
    if (
        not ctx.config.decide_here  # the paper's path alone stays the paper's
        or ctx.keyframes is None
        or inp.image is None
        or ctx.keyframes.keyframe_count() == 0
    ):
        return None
    gate = ctx.gate
    centre = None if gate is None else gate.rotation_centre
    answer = ctx.keyframes.verify(pose[None, :], inp.image, refine=True, round_centre=centre)
    if answer.index != 0 or not math.isfinite(answer.heading_std):
        return None
    return np.array([pose[0], pose[1], answer.refined_heading]), float(answer.heading_std)


def reseed(ctx: Context, inp: Inputs, visit: Visit, place: Place, dec: Decision) -> Reseed:
    """The decision picked the copy; the laser sets the pose from it, then AMCL reseeds."""
    cfg = ctx.config
    assert dec.direction is not None
    if dec.heading is not None:
        heading = float(wrap_angle(dec.heading))
    else:
        heading = wrap_angle(place.heading0 - dec.direction * 2.0 * np.pi / place.m + dec.offset)
    ctx.record.last_decision = (place, dec)
    pose = np.array([place.center[0], place.center[1], heading])
    cov = cov_from_std(cfg.decision_xy_std, cfg.decision_theta_std)
    reason = (
        f"visual decision: place {place.place_id}, direction {people(dec.direction)} of {place.m}"
    )
    gate = ctx.gate
    if gate is not None and gate.rotation_centre is not None:
        measured = _measured_again(ctx, inp, pose)
        if measured is not None:
            pose, theta_std = measured
            cov = cov_from_std(cfg.decision_xy_std, theta_std)
            reason += (
                f" (heading measured again by the keyframes, std {math.degrees(theta_std):.2f} deg)"
            )
    claim = None
    if gate is not None:
        claim = gate.confirm(pose, cov, cast(LaserScan, inp.scan))
        if claim.verdict is Verdict.WITHDRAWN:
            visit.outcomes.append(Outcome.UNDETERMINED)
            ctx.note(
                f"image {visit.attempt + 1}: direction {people(dec.direction)} of place "
                f"{place.place_id} rejected by the laser ({claim.reason})"
            )
            return Reseed(Reseeded.REJECTED, why="the laser rejected the decided pose")
        assert claim.pose is not None
        assert claim.covariance is not None
        pose, cov = claim.pose, claim.covariance
        reason += "; pose set by the laser"
    ctx.record.particles_before_decision = inp.result.particles
    reseed_tracker(ctx, pose, cov)
    ctx.note(
        f"decided direction {people(dec.direction)} of {place.m} at place {place.place_id}"
        f" (offset {math.degrees(dec.offset):+.1f} deg); AMCL reseeded"
    )
    if claim is not None and gate is not None:
        # the camera chose the copy: the claim chain starts at the decided pose whether or not
        # it is precise enough to publish yet (the gate publishes it once a scan confirms it
        # within the tolerance, as after deciding where the robot stands)
        gate.anchor(pose, cov, inp.odom_pose)
        gate.confirmed(claim, inp.odom_pose)
        if claim.verdict is Verdict.WITHHELD:
            why = (
                f"{reason}, but {claim.reason.removeprefix('claim withheld: ')}: pose "
                "published once a scan confirms it"
            )
            ctx.note(why)
            return Reseed(
                Reseeded.WITHHELD,
                Estimate(
                    status=Status.AMBIGUOUS,
                    hypotheses=(Hypothesis(pose=pose, weight=1.0),),
                    reason=why,
                ),
                why=why,
            )
    estimate = Estimate(
        status=Status.TRACKING,
        pose=pose,
        covariance=cov,
        hypotheses=(Hypothesis(pose=pose, weight=1.0),),
        reason=reason,
    )
    return Reseed(Reseeded.CLAIMED, estimate)


def unanchored(ctx: Context, place: Place, dec: Decision) -> str:
    """A direction was decided, but the place's heading reference is odometry's: no claim.

    Returns why the pose stays undetermined."""
    ctx.record.last_decision = (place, dec)
    ctx.note(
        f"decided direction {people(dec.direction)} of {place.m} at place"
        f" {place.place_id}, but its stored "
        "headings came from odometry (not observable by the laser when it was mapped)"
    )
    return (
        "undetermined: the visual map of this place has no reliable heading reference "
        "(mapped where laser SLAM cannot observe heading); pose not claimed"
    )


def conclusion(ctx: Context, visit: Visit) -> str | None:
    """Every direction was tried: None when the place should be mapped (nothing matched and
    mapping is allowed), else why the pose stays undetermined."""
    outcomes = set(visit.outcomes)
    nothing_matched = outcomes <= {Outcome.NO_PLACE, Outcome.NO_MATCH}
    # a circle is not mapped here (any heading fits its images equally)
    if nothing_matched and ctx.config.allow_mapping and (visit.order.k or 0) >= 2:
        return None
    if Outcome.REFUSED in outcomes and len(outcomes) == 1:
        return "undetermined: the images have too few features to decide"
    if nothing_matched:
        return "undetermined: no visual map matches this place (mapping not allowed)"
    return f"undetermined: no clear visual decision in {visit.m} directions"


def store_mapped_place(ctx: Context, visit: Visit) -> Place:
    """Add the mapped place (its images and their measured headings) to the visual map and
    to the known places."""
    run = visit.mapping
    assert run is not None
    assert run.heading0 is not None
    place = ctx.places.add_place(
        visit.centre_map,
        run.heading0,
        visit.order,
        visit.gv,
        visit.kind,
        list(run.images),
        headings=list(run.headings),
    )
    ctx.known_places.append(place)
    return place
