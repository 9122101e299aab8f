"""Algorithm 5's phases as state objects.

Each phase owns its counters and data and has one method, ``step(ctx, inp)``, that returns the
scan's :class:`~symloc.localizer.types.Estimate` and the next phase (itself to stay):

- :class:`Lost`: nothing earned; AMCL must converge where the scan is not symmetric.
- :class:`Tracking`: earned; every pose passes the claim gate.
- :class:`Centering`, :class:`Facing` (Algorithm 2): going to the centre of the symmetric
  place, then facing the middle between two adjacent corners.
- :class:`Capture`, :class:`Rotating` (Algorithm 3): an image per direction, turning clockwise
  by 360/M between them; or mapping the place (Algorithm 5 step 11).
- :class:`Settled`: ambiguous, nothing more to try until the robot leaves the place.

Leaving :class:`Tracking` forgets the claim chain: the localizer's transition does it, in one
place (:meth:`symloc.localizer.localizer.Localizer.update`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import ClassVar, Protocol, cast

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import angle_diff, compose, inverse
from symloc.scan import LaserScan
from symloc.symmetry.order import SymmetryOrder

from . import deciding
from .centering import CentreFilter
from .claim import Claim, Standing, Verdict
from .config import LocalizerConfig
from .context import (
    Context,
    Inputs,
    MappingRun,
    Visit,
    ambiguous,
    cov_from_std,
    lost,
    tracking,
)
from .copies import (
    CopiesKind,
    copies_fit,
    copies_verdict,
    known_place_at,
    rotated_copies,
    symmetry_consistent,
)
from .operator_veto import OperatorVeto, VetoKind
from .rules import Streak
from .types import (
    Estimate,
    Hypothesis,
    Place,
    Request,
    RequestKind,
    Status,
)
from .withheld_axis import withheld_axis

__all__ = [
    "Capture",
    "Centering",
    "Facing",
    "Lost",
    "Phase",
    "Rotating",
    "Settled",
    "Tracking",
    "restart",
]


class Phase(Protocol):
    """One phase of Algorithm 5: ``name`` for logs and tests, ``step`` for one scan."""

    name: ClassVar[str]

    def step(self, ctx: Context, inp: Inputs) -> tuple[Estimate, Phase]:
        """The scan's estimate and the next phase."""
        ...


Step = tuple[Estimate, Phase]


def restart(ctx: Context) -> Lost:
    """Start over: nothing earned, no counters, the claim gate's lifecycle forgotten."""
    ctx.restart()
    return Lost.fresh(ctx.config)


# --------------------------------------------------------------------------- LOST, TRACKING


@dataclass
class Lost:
    """Nothing earned yet.

    ``converged`` counts AMCL's converged updates (the pose is earned at
    ``converged_updates``); ``contradicted`` the filter updates at which the scan contradicts
    AMCL's estimate (AMCL is spread over the map again at ``relocalize_after``).
    """

    name: ClassVar[str] = "lost"
    converged: Streak
    contradicted: Streak

    @classmethod
    def fresh(cls, config: LocalizerConfig) -> Lost:
        """Counters at zero."""
        return cls(Streak(config.converged_updates), Streak(config.relocalize_after))

    def step(self, ctx: Context, inp: Inputs) -> Step:
        result, verdict = inp.result, inp.verdict
        if verdict.symmetric and verdict.center is not None:
            return start_ambiguity(ctx, inp, "scan symmetric, pose not earned")
        if result.confident:  # the tracker's verdict (symloc.mcl.confidence)
            found = copies_ambiguity(ctx, inp, self, result.estimate)
            if found is not None:
                return found
            if self.converged.hit():
                ctx.note("AMCL converged where the scan is not symmetric: pose earned")
                return Tracking(self).claim(ctx, inp, "AMCL converged; scan not symmetric")
            return lost("AMCL converging", result), self
        self.converged.miss()
        gate = ctx.gate
        if result.updated and gate is not None:
            scan = cast(LaserScan, inp.scan)
            if gate.check(inp.odom_pose, scan).verdict is Verdict.WITHDRAWN:
                self.contradicted.hit()
            else:
                self.contradicted.miss()
        if self.contradicted.reached:
            ctx.tracker.initialize_global()
            if gate is not None:
                gate.reset()
            self.contradicted.reset()
            ctx.note(
                f"the scan contradicted AMCL's estimate for {ctx.config.relocalize_after} "
                "updates: global relocalization"
            )
            return lost("AMCL not converged; relocalizing globally", result), self
        return lost("AMCL not converged", result), self


@dataclass
class Tracking:
    """The pose is earned; each scan's pose is published only if the claim gate confirms it.

    ``lost`` holds :class:`Lost`'s counters as they were when the pose was earned (the copy
    check of the first claim goes on with them); a pose lost while tracking starts them afresh,
    so it is earned again only after ``converged_updates`` converged updates.
    """

    name: ClassVar[str] = "tracking"
    lost: Lost
    veto: OperatorVeto = field(default_factory=OperatorVeto)
    #: entered at an operator's pose: earned only once a claim is confirmed (its copies
    #: were never checked)
    from_operator: bool = False

    def step(self, ctx: Context, inp: Inputs) -> Step:
        cfg = ctx.config
        result, verdict = inp.result, inp.verdict
        if verdict.symmetric and verdict.center is not None and verdict.order is not None:
            n = symmetry_consistent(
                result.hypotheses,
                inp.centre_in_map(),
                verdict.order,
                min_weight=cfg.min_cluster_weight,
                position_tol=cfg.symmetry_position_tol,
                angle_tol=cfg.symmetry_angle_tol,
            )
            if n >= 2:
                why = f"AMCL split into {n} clusters related by the symmetry"
                return start_ambiguity(ctx, inp, why)
        if not result.hypotheses or result.hypotheses[0].weight < cfg.min_cluster_weight:
            ctx.note("AMCL lost its pose")
            return lost("AMCL has no well-weighted cluster", result), Lost.fresh(cfg)
        return self.claim(ctx, inp, "AMCL tracking")

    def claim(self, ctx: Context, inp: Inputs, reason: str) -> Step:
        """Publish the tracker's estimate if the claim gate confirms it at this scan."""
        result = inp.result
        gate = ctx.gate
        if gate is None:
            return tracking(result, reason), self
        ruling = gate.step(result, inp.odom_pose, cast(LaserScan, inp.scan), ctx.tracker, ctx.note)
        claim = ruling.claim
        if ruling.standing is Standing.FIRST:
            assert claim is not None
            assert claim.pose is not None
            found = copies_ambiguity(ctx, inp, self.lost, claim.pose)
            if found is not None:
                return found
            gate.confirmed(claim, inp.odom_pose)
        if ruling.standing is Standing.OPERATOR:
            assert claim is not None
            assert claim.pose is not None
            veto = self.veto.judge(ctx, inp, claim.pose)
            if veto.kind is VetoKind.LOOK:
                why = "a rotated copy of the operator's pose fits the scan as well: image requested"
                return (
                    Estimate(
                        status=Status.LOST,
                        hypotheses=result.hypotheses,
                        request=Request(RequestKind.CAPTURE_IMAGE),
                        reason=why,
                    ),
                    self,
                )
            if veto.kind is VetoKind.VETOED:
                gate.forget_operator()
                ctx.note(veto.reason)
                found = copies_ambiguity(ctx, inp, self.lost, claim.pose)
                if found is not None:
                    return found
                return lost(veto.reason, result), restart(ctx)
            gate.confirmed(claim, inp.odom_pose)
        if ruling.standing in (Standing.FIRST, Standing.OPERATOR, Standing.PUBLISH):
            assert claim is not None
            assert claim.pose is not None
            assert claim.covariance is not None
            estimate = Estimate(
                status=Status.TRACKING,
                pose=claim.pose,
                covariance=claim.covariance,
                hypotheses=result.hypotheses,
                reason=reason,
            )
            return estimate, self
        if ruling.standing is Standing.UNEARNED:
            # a pose the laser never confirmed (an operator's initial pose, a reseed) was
            # contradicted or abandoned by the filter: whatever the filter converges to next
            # must be earned like any other, not published because the phase says tracking
            ctx.note(f"unconfirmed pose given up: {ruling.reason}; the pose must be earned")
            return lost(f"unconfirmed pose given up: {ruling.reason}", result), restart(ctx)
        if ruling.standing is Standing.RELOCALIZE:
            fresh = restart(ctx)
            ctx.note(ruling.reason)
            return lost(ruling.reason, result), fresh
        earned = not self.from_operator or gate.has_chain
        axis = (
            withheld_axis(gate, claim, earned)
            if inp.turn_rate <= ctx.config.axis_max_turn
            else None
        )
        estimate = axis if axis is not None else lost(ruling.reason, result)
        request = precision_request(ctx, claim, earned)
        if request is not None:
            estimate = replace(estimate, request=request)
        return estimate, self


def precision_request(ctx: Context, claim: Claim | None, earned: bool) -> Request | None:
    """A ``GO_TO`` request towards the map's middle, where its scale error and a round map's
    rotation cost nothing in position (the next waypoint, in the robot frame of ``claim``'s
    pose, of the route through free space to :meth:`ClaimGate.precise_place`:
    :meth:`ClaimGate.precise_route`) when ``claim`` (of an ``earned`` pose, claims not
    suspended) was withheld because its distance from there alone makes it too imprecise
    (:meth:`ClaimGate.middle_bound`); else None (``LocalizerConfig.precision_drive``)."""
    gate = ctx.gate
    cfg = ctx.config
    if not cfg.precision_drive or gate is None or claim is None or claim.pose is None:
        return None
    if not earned or gate.suspended or not gate.middle_bound(claim):
        return None
    route = gate.precise_route(cfg.precision_clearance)
    place = None if route is None else route.waypoint(claim.pose[:2], cfg.precision_lookahead)
    if place is None:
        return None
    target = compose(inverse(claim.pose), np.array([place[0], place[1], 0.0]))[:2]
    return Request(RequestKind.GO_TO, target=np.asarray(target, dtype=np.float64))


def copies_ambiguity(
    ctx: Context, inp: Inputs, back: Lost, pose: NDArray[np.float64]
) -> Step | None:
    """None when no rotated copy of ``pose`` (about a known symmetric place's centre or a
    near symmetry of the map) explains the scan about as well; else the step that says so
    (going to the place's centre, or ambiguous among the map's copies in ``back``, AMCL
    reseeded at a copy that fits clearly better). Every pose is checked so before it is
    first published: on convergence, and when a claim chain starts while tracking."""
    cfg = ctx.config
    gate, scorer, ratio = ctx.gate, ctx.scorer, cfg.copy_score_ratio
    floor, slack = cfg.copy_claim_floor, cfg.copy_map_slack
    place = known_place_at(pose, ctx.known_places, cfg.place_radius_factor)
    if place is not None and copies_fit(
        pose,
        place.center,
        place.order,
        inp.scan,
        gate=gate,
        scorer=scorer,
        ratio=ratio,
        floor=floor,
        slack=slack,
    ):
        back.converged.reset()
        return start_ambiguity_at_place(ctx, inp, place)
    for sym in ctx.map_symmetries:
        sym_order = SymmetryOrder.finite(sym.order)
        verdict = copies_verdict(
            pose,
            sym.centre,
            sym_order,
            inp.scan,
            gate=gate,
            scorer=scorer,
            ratio=ratio,
            floor=floor,
            slack=slack,
        )
        if verdict.kind is CopiesKind.UNIQUE:
            continue
        back.converged.reset()
        copies = rotated_copies(pose, sym.centre, sym_order)
        if verdict.kind is CopiesKind.BETTER:
            assert verdict.index is not None
            # a rotated copy explains the scan clearly better: AMCL chose wrong
            ctx.tracker.initialize_pose(
                copies[verdict.index], cov_from_std(cfg.reseed_xy_std, cfg.reseed_theta_std)
            )
            why = (
                f"a rotated copy (order {sym.order}) of AMCL's pose explains the scan "
                "clearly better: AMCL reseeded there, pose not earned yet"
            )
        else:
            what = "part of the map is" if sym.partial else "the map itself is"
            why = (
                f"{what} symmetric (order {sym.order}, overlap "
                f"{100 * sym.overlap:.0f} %) and a rotated copy of AMCL's pose explains "
                "the scan about as well: pose not earned"
            )
        ctx.notes.note_once(why)
        estimate = Estimate(
            status=Status.AMBIGUOUS,
            hypotheses=tuple(Hypothesis(pose=p, weight=1.0 / len(copies)) for p in copies),
            order=sym_order,
            reason=why,
        )
        return estimate, back
    return None


# --------------------------------------------------------------------------- Algorithm 2


def start_ambiguity(ctx: Context, inp: Inputs, why: str) -> Step:
    """The scan is symmetric and the pose not earned: go to the centre it shows."""
    result, verdict = inp.result, inp.verdict
    ctx.record.particles_at_ambiguity = result.particles
    order = verdict.order
    assert order is not None  # a symmetric verdict has an order
    gv = float(verdict.gv_distance)
    centre = CentreFilter(alpha=ctx.config.centre_smoothing)
    target = np.asarray(verdict.center, dtype=np.float64)
    centre.update(inp.odom_pose, target[:2])
    found = [p for p in ctx.places.candidates(gv, order) if p.order == order]
    visit = Visit(
        order=order,
        gv=gv,
        kind=verdict.kind,
        centre_map=inp.centre_in_map(),
        centre=centre,
        place=found[0] if len(found) == 1 else None,
        flips=Streak(ctx.config.flip_patience),
    )
    ctx.note(f"ambiguous (order {order}): {why}; going to the centre")
    estimate = ambiguous(
        inp,
        visit,
        Status.AMBIGUOUS,
        Request(RequestKind.GO_TO_CENTRE, target=np.asarray(verdict.center, dtype=float)),
        f"{why}; order {order}",
    )
    return estimate, Centering(visit)


def start_ambiguity_at_place(ctx: Context, inp: Inputs, place: Place) -> Step:
    """Rotated copies of the pose about a known symmetric place fit the map: go to its centre."""
    result = inp.result
    ctx.record.particles_at_ambiguity = result.particles
    centre = CentreFilter(alpha=ctx.config.centre_smoothing)
    # every rotated copy of the estimate sees the place's centre at the same base-frame point
    centre_base = compose_inverse(result.estimate, place.center)
    centre.update(inp.odom_pose, centre_base)
    visit = Visit(
        order=place.order,
        gv=place.gv_distance,
        kind=place.kind,
        centre_map=np.asarray(place.center, dtype=np.float64),
        centre=centre,
        place=place,
        flips=Streak(ctx.config.flip_patience),
    )
    why = f"inside known symmetric place {place.place_id}: rotated copies fit the map"
    ctx.note(f"ambiguous (order {visit.order}): {why}")
    estimate = ambiguous(
        inp, visit, Status.AMBIGUOUS, Request(RequestKind.GO_TO_CENTRE, target=centre_base), why
    )
    return estimate, Centering(visit)


def compose_inverse(pose: NDArray[np.float64], point: NDArray[np.float64]) -> NDArray[np.float64]:
    """``point`` (2,) in the map frame seen from ``pose`` (3,): its base-frame position (2,)."""
    return np.asarray(compose(inverse(pose), np.array([*point, 0.0]))[:2])


def follow_centre(ctx: Context, inp: Inputs, visit: Visit) -> bool:
    """Update the target from a symmetric verdict; False when the verdict flipped for good."""
    verdict = inp.verdict
    if verdict.symmetric and verdict.center is not None:
        visit.flips.miss()
        visit.centre.update(inp.odom_pose, np.asarray(verdict.center, dtype=np.float64)[:2])
        visit.gv = float(verdict.gv_distance)
        return True
    return not visit.flips.hit()


def abandon(ctx: Context, inp: Inputs, why: str) -> Step:
    """Give up the trip to the centre: start over."""
    ctx.note(f"gave up the trip to the centre: {why}")
    return lost(why, inp.result), restart(ctx)


def trip_failed(
    ctx: Context, inp: Inputs, visit: Visit, updates: int, too_long: str
) -> Step | None:
    """The step that gives up the trip to the centre at its ``updates``-th scan (the scan no
    longer symmetric, or ``max_centering_updates`` passed: ``too_long`` says why), else None."""
    if not follow_centre(ctx, inp, visit):
        return abandon(ctx, inp, "the scan is no longer judged symmetric")
    if updates > ctx.config.max_centering_updates:
        return abandon(ctx, inp, too_long)
    return None


@dataclass
class Centering:
    """Going to the centre; ``updates`` counts this trip's scans (and facing's)."""

    name: ClassVar[str] = "centering"
    visit: Visit
    updates: int = 0

    def step(self, ctx: Context, inp: Inputs) -> Step:
        self.updates += 1
        failed = trip_failed(ctx, inp, self.visit, self.updates, "did not reach the centre in time")
        if failed is not None:
            return failed
        target = self.visit.centre.update(inp.odom_pose, None)
        assert target is not None
        distance = float(np.hypot(*target))
        if distance <= ctx.config.centre_tolerance and inp.verdict.symmetric:
            ctx.note("reached the centre")
            return Facing(self.visit, self.updates).step(ctx, inp)
        estimate = ambiguous(
            inp,
            self.visit,
            Status.GOING_TO_CENTRE,
            Request(RequestKind.GO_TO_CENTRE, target=target),
            f"going to the centre ({1000 * distance:.0f} mm away)",
        )
        return estimate, self


@dataclass
class Facing:
    """At the centre, turning to face the middle between two adjacent corners."""

    name: ClassVar[str] = "facing"
    visit: Visit
    updates: int = 0

    def step(self, ctx: Context, inp: Inputs) -> Step:
        self.updates += 1
        too_long = "could not face the corner middle in time"
        failed = trip_failed(ctx, inp, self.visit, self.updates, too_long)
        if failed is not None:
            return failed
        verdict = inp.verdict
        facing = verdict.facing if verdict.symmetric else None
        if facing is None or abs(facing) <= ctx.config.facing_tolerance:
            return begin_capture(ctx, inp, self.visit)
        estimate = ambiguous(
            inp,
            self.visit,
            Status.GOING_TO_CENTRE,
            Request(RequestKind.FACE_DIRECTION, angle=float(facing)),
            "at the centre; facing the middle between two adjacent corners",
        )
        return estimate, self


# --------------------------------------------------------------------------- Algorithm 3


def begin_capture(ctx: Context, inp: Inputs, visit: Visit) -> Step:
    """Facing a corner middle: ask for an image."""
    if visit.m == 0:
        visit.m = deciding.directions(ctx, visit)
    estimate = ambiguous(
        inp,
        visit,
        Status.DECIDING,
        Request(RequestKind.CAPTURE_IMAGE),
        f"at the centre; image {visit.attempt + 1} of {visit.m} requested",
    )
    return estimate, Capture(visit)


@dataclass
class Capture:
    """Waiting for the image, then deciding it (or storing it, when mapping the place)."""

    name: ClassVar[str] = "capture"
    visit: Visit

    def step(self, ctx: Context, inp: Inputs) -> Step:
        visit = self.visit
        if inp.image is None:
            request = Request(RequestKind.CAPTURE_IMAGE)
            return ambiguous(inp, visit, Status.DECIDING, request, "waiting for the image"), self
        if visit.mapping is not None:
            return collect_mapping_image(ctx, inp, visit, visit.mapping, inp.image)
        choice = deciding.choose(ctx, visit, inp.image)
        if choice.place is None or choice.decision is None:
            return next_attempt(ctx, inp, visit, choice.retry)
        if not choice.place.heading_reliable:
            return settle(ctx, inp, visit, deciding.unanchored(ctx, choice.place, choice.decision))
        done = deciding.reseed(ctx, inp, visit, choice.place, choice.decision)
        if done.outcome is deciding.Reseeded.REJECTED:
            return next_attempt(ctx, inp, visit, done.why)
        assert done.estimate is not None
        return done.estimate, Tracking(restart(ctx))


def next_attempt(ctx: Context, inp: Inputs, visit: Visit, why: str) -> Step:
    """Turn clockwise to the next direction, or conclude when every direction was tried."""
    visit.attempt += 1
    if visit.attempt >= visit.m:
        return conclude(ctx, inp, visit)
    # a polygon squares up on the next corner middle after the turn; a circle has none, and
    # a query half-way between two stored views scores both alike, so it turns half a step
    step = 2.0 * np.pi / visit.m if not visit.order.is_circle else np.pi / visit.m
    rotating = Rotating(visit, float(inp.odom_pose[2]), -step)
    estimate = ambiguous(
        inp,
        visit,
        Status.DECIDING,
        Request(RequestKind.ROTATE, angle=rotating.angle),
        f"attempt {visit.attempt}: {why}; turning clockwise by {np.degrees(step):.0f} deg",
    )
    return estimate, rotating


@dataclass
class Rotating:
    """Turning by ``angle`` [rad] (clockwise: negative) from odometry heading ``start``."""

    name: ClassVar[str] = "rotating"
    visit: Visit
    start: float
    angle: float

    def step(self, ctx: Context, inp: Inputs) -> Step:
        turned = float(angle_diff(inp.odom_pose[2], self.start))
        remaining = float(angle_diff(self.angle, turned))
        if abs(remaining) <= ctx.config.rotate_tolerance:
            return Facing(self.visit).step(ctx, inp)
        estimate = ambiguous(
            inp,
            self.visit,
            Status.DECIDING,
            Request(RequestKind.ROTATE, angle=remaining),
            f"turning to direction {self.visit.attempt + 1} of {self.visit.m}",
        )
        return estimate, self


def conclude(ctx: Context, inp: Inputs, visit: Visit) -> Step:
    """Every direction tried: map the place (Algorithm 5 step 11) or settle."""
    why = deciding.conclusion(ctx, visit)
    if why is not None:
        return settle(ctx, inp, visit, why)
    visit.mapping = MappingRun()
    visit.attempt = 0
    ctx.note("no visual map matches this place: building one (Algorithm 5 step 11)")
    estimate = ambiguous(
        inp,
        visit,
        Status.DECIDING,
        Request(RequestKind.CAPTURE_IMAGE),
        f"no visual map matches: mapping this place, image 1 of {visit.m}",
    )
    return estimate, Capture(visit)


def collect_mapping_image(
    ctx: Context, inp: Inputs, visit: Visit, run: MappingRun, image: NDArray[np.uint8]
) -> Step:
    """Store one image of the place being mapped; turn for the next or store the place."""
    heading = float(inp.result.estimate[2])
    if run.heading0 is None:
        run.heading0 = heading
    run.images.append(image)
    run.headings.append(heading)
    if len(run.images) < visit.m:
        visit.attempt = len(run.images)
        rotating = Rotating(visit, float(inp.odom_pose[2]), -2.0 * np.pi / visit.m)
        estimate = ambiguous(
            inp,
            visit,
            Status.DECIDING,
            Request(RequestKind.ROTATE, angle=rotating.angle),
            f"mapping this place: turning clockwise for image {visit.attempt + 1}",
        )
        return estimate, rotating
    place = deciding.store_mapped_place(ctx, visit)
    visit.mapping = None
    return settle(
        ctx,
        inp,
        visit,
        f"new visual map built for place {place.place_id}; its heading reference is "
        f"AMCL's choice among {visit.order} symmetric copies, so the pose stays ambiguous",
    )


# --------------------------------------------------------------------------- SETTLED


def settle(ctx: Context, inp: Inputs, visit: Visit, why: str) -> Step:
    """Ambiguous, nothing more to try here."""
    settled = Settled(visit, why, Streak(ctx.config.flip_patience))
    ctx.note(why)
    return ambiguous(inp, visit, Status.AMBIGUOUS, None, why), settled


@dataclass
class Settled:
    """Ambiguous for ``reason``, until ``flips`` non-symmetric scans in a row say the robot
    left the place (then AMCL relocalizes globally)."""

    name: ClassVar[str] = "settled"
    visit: Visit
    reason: str
    flips: Streak

    def step(self, ctx: Context, inp: Inputs) -> Step:
        if inp.verdict.symmetric:
            self.flips.miss()
        elif self.flips.hit():
            ctx.tracker.initialize_global()
            fresh = restart(ctx)
            ctx.note("left the symmetric place: global AMCL, pose must be earned again")
            return lost("left the symmetric place; relocalizing", inp.result), fresh
        return ambiguous(inp, self.visit, Status.AMBIGUOUS, None, self.reason), self
