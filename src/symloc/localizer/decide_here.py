"""Deciding from where the robot stands: the laser proposes, the camera decides.

With ``LocalizerConfig.decide_here`` set, whenever the pose is not earned (lost at start-up or
after a kidnapping, AMCL not converging, a symmetric scan, a symmetric map leaving rotated
copies open) the localizer first tries to decide without driving anywhere:

1. **The laser proposes** (:func:`propose`): AMCL's clusters, the global scan-to-map search's
   candidates (:class:`~symloc.localizer.types.PoseProposer`) and their rotated copies about
   the map's symmetries and the known symmetric places; each is aligned to the map by the
   claim gate's scan matcher and scored by the share of beams that then fit.
2. **One survivor** (within ``decide_laser_margin`` of the best, the search complete, and no
   rotated copy of it that the copy check would not rule out: such a copy survives too, or
   the check would refuse the pose): the laser sets the pose (:meth:`ClaimGate.confirm`) and
   it is claimed at this scan when the gate claims it and the copy check of every first
   claim (:func:`~.phases.copies_ambiguity`) finds no copy; otherwise (withheld, refused)
   AMCL is reseeded there and the pose is earned as always, through
   :class:`~.phases.Lost`'s copy checks and the claim gate.
3. **Several survivors**: the robot turns in place to where the keyframes are
   (:func:`~symloc.localizer.view_planning.plan_turn`: the heading at which the most
   hypotheses predict keyframes, at least ``decide_turn`` from every heading already
   imaged), the laser proposes again and an image is requested; the hypotheses, carried by
   odometry to the moment of the image, are verified against the visual map's keyframes
   (:class:`~symloc.localizer.types.KeyframeStore`). Exactly one verified with margin, or
   several that are one pose (:mod:`~symloc.localizer.verified_together`: neighbouring
   samples of a round room's family, which the laser sets within the tolerance of each other
   from the camera's heading; on a round map every fit measures a member of the family, and
   the robot first drives to within ``decide_round_reach`` of the centre, where the heading
   costs nothing in position, and the decided member's heading must be measured again by
   planar motion or another view is taken): the laser sets the pose from it
   (:meth:`ClaimGate.confirm`),
   AMCL is reseeded there, and the pose is published only if the gate claims it. The camera
   cannot overrule the laser about a hypothesis no image checked: a survivor that no image of
   this episode could check (no keyframe where it says the camera looks; none contradicted
   it, carried by odometry from an earlier view, :func:`contradicted_before`) blocks the
   decision when the laser ranks it at least as high as the verified one (the verified one
   may be a look-alike: a repeated texture), and the next view turns first to where such
   hypotheses expect keyframes. Otherwise the robot looks elsewhere the same way, up to
   ``decide_views`` images; where no heading shows a keyframe to any hypothesis, no image is
   taken. Along an axis each sampled hypothesis stands for the stretch around it: its
   expected keyframes reach half the spacing further (``KeyframeStore.verify``'s ``reach``).
   **Without keyframes, or when the camera decides nothing** (no keyframe in view of any
   hypothesis, or its ``decide_views`` used up; the search complete or no camera at all,
   the scan not judged symmetric, no known place where the robot stands), the laser watches
   the survivors as the robot moves (:mod:`symloc.localizer.laser_watch`): each carried by
   odometry and aligned at every scan, the beams each explains summed over new views. When
   every rival's deficit against the leader adds up to ``decide_watch_evidence`` (a room
   symmetric but for a piece of furniture), the laser confirms the leader and tracking starts
   there, as after a visual decision; the status is ``ambiguous`` meanwhile, with the
   hypotheses. After
   ``decide_watch_views`` views without a decision, or when moving teaches nothing (a
   perfectly symmetric room, a robot standing still), the path gives up as in step 4.
   **Without a camera, one survivor of a search that cannot be complete** (an open map: the
   robot may stand where the map does not reach) is not claimed by the laser, but AMCL is
   reseeded there and the pose earned as any convergence of AMCL is: a tracking filter's
   particles spread over a large map never converge (freiburg-079, 70 x 100 m, at seed 2:
   lost for the last 3,600 scans, while the one pose these episodes left was within 6 cm and
   1 deg of the log's corrected pose in each of the nine traced up to scan 2,600). Several
   survivors of such a search are watched as above, and the leader the watch singles out is
   reseeded the same way, never claimed (the truth may be none of them). Without a camera
   deciding here rests ``decide_rest_no_camera`` scans, not ``decide_rest``: AMCL, the only
   other phase, runs at every scan anyway.
4. **Nothing decided**: the pose stays lost (or ambiguous, with the hypotheses) with a reason,
   and for ``decide_rest`` scans the other phases run as without this path: AMCL converging,
   or the paper's drive to the centre of a symmetric place (Algorithms 2 and 3).

**A corridor whose ends the scan sees** (the survivors an axis family only because an end
wall's few beams are less than the search's margin): :func:`~.axis_pin.pin_axis` profiles
the scan's fit along each heading class' line and, where one stretch fits clearly best, the
class is the one pose aligned there; the two poses go on as several survivors (step 3).
On by default (``LocalizerConfig.axis_pin_gain`` = :data:`~.axis_pin.PIN_GAIN`; 1 turns it off).

**A corridor** (the survivors are an axis family, :mod:`symloc.localizer.axis`: one heading up
to a half turn, along a line): no single pose can be verified, since the camera does not tell
where along the corridor it stands. Hypotheses along both heading classes' segments are shown
to the camera instead, and the image decides the heading class
(:mod:`symloc.localizer.axis_heading`); the localizer then reports status ``axis``
(:mod:`symloc.localizer.axis_phase`), and comes back here every ``axis_recheck`` scans to earn
a full pose as above (with the axis as the phase to return to: an axis family with its
heading renews it without an image; a pose verified against the axis' heading is refused).

:class:`DecideRouter` is the one place that sends the localizer here: before a scan is given
to :class:`~.phases.Lost` (or to a trip to the centre that has not started), unless the path
is resting.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar, cast

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import angle_diff, compose, relative, wrap_angle
from symloc.scan import LaserScan
from symloc.symmetry.order import SymmetryOrder

from .axis_heading import vote_heading
from .axis_phase import AxisClass, OnAxis, axis_classes, enter_axis
from .axis_pin import pin_axis
from .claim import Claim, Verdict
from .config import LocalizerConfig
from .context import Context, Inputs, cov_from_std, lost, reseed_tracker
from .copies import CopyScores, claim_floor, known_place_at, rotated_copies
from .laser_watch import LaserWatch, WatchVerdict
from .phases import Centering, Lost, Phase, Step, Tracking, copies_ambiguity, restart
from .types import (
    Estimate,
    Hypothesis,
    KeyframeStore,
    Request,
    RequestKind,
    Status,
    Verification,
)
from .verified_together import implied_pose, one_pose_verified
from .view_planning import plan_turn

__all__ = ["AxisVote", "DecideHere", "DecideRouter", "Hypotheses", "propose"]

FloatArray = NDArray[np.float64]

#: Two hypotheses closer than this [m] and turned less than :data:`SAME_ANGLE` are one.
SAME_DISTANCE = 0.2
SAME_ANGLE = math.radians(10.0)
#: Scans an image may take to arrive before the path gives up (no camera answering).
IMAGE_PATIENCE = 3
#: Scans in a row that no pose explains, the robot held still, before the path gives up. A
#: scan that fits nowhere is the scan's fault more often than the robot's (a person right at
#: the lidar hides the room; a scan swept in a fast turn is skewed): the first such scan gave
#: the episode up, and the robot drove on before the next one (unused dev circle#18, where the
#: bench let a person walk through the robot: every scan inside the person fitted 23-38 % of
#: its beams at every pose listed). Nothing is published meanwhile. What it changes on the
#: bench once people step aside is not measured apart (dev realistic at eeec748: the same
#: counts per family as without it).
UNEXPLAINED_PATIENCE = 3
#: Turns in place per image allowed before the path gives up (re-planned views that never
#: settle).
TURNS_PER_VIEW = 2
#: Scans a drive to a round room's centre may take (30 s at 10 Hz; the bench drives 0.3 m/s
#: in rooms up to 8 m across) before deciding from wherever the robot got to ...
ROUND_PATIENCE = 300
#: ... or scans without getting 2 cm closer (a table at the centre, a person in the way: the
#: driver stops short of obstacles; a turn in place first takes 2-3 s).
ROUND_STALL = 50
#: A heading class of a new axis family is the axis' own when within this [rad] of it.
SAME_CLASS = math.pi / 4


@dataclass(frozen=True, eq=False)
class Hypotheses:
    """:func:`propose`'s answer: ``poses`` (K, 3) aligned to the map, best first, with the
    share of beams each explains (``fits`` (K,)); ``survivors`` how many of the first lie
    within the laser's margin of the best; ``complete`` False when the laser may have missed
    poses that explain the scan as well (so one survivor is not enough)."""

    poses: FloatArray
    fits: FloatArray
    survivors: int
    complete: bool
    reason: str = ""


def _distinct(poses: FloatArray) -> FloatArray:
    """``poses`` (K, 3) without the later ones that repeat an earlier one."""
    keep: list[int] = []
    for i in range(poses.shape[0]):
        p = poses[i]
        same = any(
            math.hypot(*(poses[j, :2] - p[:2])) < SAME_DISTANCE
            and abs(float(wrap_angle(poses[j, 2] - p[2]))) < SAME_ANGLE
            for j in keep
        )
        if not same:
            keep.append(i)
    return poses[keep]


def propose(ctx: Context, inp: Inputs) -> Hypotheses:
    """The laser's hypotheses for this scan (see the module docstring, step 1)."""
    cfg = ctx.config
    found: list[FloatArray] = []
    complete = True
    reason = ""
    if ctx.proposer is not None:
        proposal = ctx.proposer.propose(inp.scan)
        found.extend(np.asarray(p, dtype=np.float64) for p in proposal.poses)
        complete, reason = proposal.complete, proposal.reason
    else:
        complete, reason = False, "no global search"
    found.extend(
        np.asarray(h.pose, dtype=np.float64)
        for h in inp.result.hypotheses
        if h.weight >= cfg.min_cluster_weight
    )
    seeds = list(found)
    for pose in seeds:
        for sym in ctx.map_symmetries:
            found.extend(rotated_copies(pose, sym.centre, SymmetryOrder.finite(sym.order))[1:])
        place = known_place_at(pose, ctx.known_places, cfg.place_radius_factor)
        if place is not None:
            found.extend(rotated_copies(pose, place.center, place.order)[1:])
    if not found:
        return Hypotheses(np.zeros((0, 3)), np.zeros(0), 0, complete, "no pose explains the scan")
    poses = _distinct(np.array(found, dtype=np.float64))
    aligned, fits = _align(ctx, inp, poses)
    order = np.argsort(-fits, kind="stable")
    aligned, fits = _distinct_fits(aligned[order], fits[order])
    keep = fits >= cfg.decide_min_fit
    aligned, fits = (
        aligned[keep][: cfg.decide_max_hypotheses],
        fits[keep][: cfg.decide_max_hypotheses],
    )
    if fits.size == 0:
        return Hypotheses(aligned, fits, 0, complete, "no pose explains the scan")
    survivors = int(np.count_nonzero(fits >= fits[0] - cfg.decide_laser_margin))
    survivors = max(survivors, _open_copies(ctx, inp, aligned, fits))
    return Hypotheses(aligned, fits, survivors, complete, reason)


@dataclass(frozen=True, eq=False)
class Checked:
    """One image's verdict on one hypothesis: its map ``pose`` (3,) when the image was taken,
    the odometry pose ``odom`` (3,) then, and whether the image contradicted it."""

    pose: FloatArray
    odom: FloatArray
    contradicted: bool


def checked_by(
    poses: FloatArray,
    odom: FloatArray,
    answer: Verification,
    centre: FloatArray | None = None,
) -> list[Checked]:
    """The verdicts of ``answer`` on the hypotheses ``poses`` (K, 3) the image checked
    (verified or contradicted; not those it could not check), at odometry pose ``odom``. On
    a round map (``centre`` (2,) [m], its rotation centre) a verified hypothesis is recorded
    as the member of the room's family its fit measured (:func:`implied_pose`)."""
    out = []
    for i, c in enumerate(answer.checks):
        if c.status not in ("verified", "contradicted"):
            continue
        pose = poses[i].copy()
        if centre is not None and c.verified and math.isfinite(c.heading_offset):
            pose = implied_pose(pose, c.heading_offset, centre)
        out.append(Checked(pose, np.asarray(odom, dtype=np.float64).copy(), not c.verified))
    return out


def _other_members(
    before: list[Checked], pose: FloatArray, odom: FloatArray, tolerance: float
) -> list[int]:
    """On a round map, which earlier verified members (1-based, in ``before``'s order),
    carried by odometry to ``odom`` (3,), are another member of the family than the decided
    ``pose`` (3,): their heading more than ``tolerance`` [rad] from its (a heading is a
    member)."""
    out = []
    for k, c in enumerate(before):
        now = np.asarray(compose(c.pose, relative(c.odom, odom)), dtype=np.float64)
        if abs(float(angle_diff(now[2], pose[2]))) > tolerance:
            out.append(k + 1)
    return out


def contradicted_before(
    checked: list[Checked], pose: FloatArray, odom: FloatArray, cfg: LocalizerConfig
) -> bool:
    """True when an earlier image contradicted the hypothesis ``pose`` (3,) (map frame, at
    odometry pose ``odom``): a checked pose carried by the odometry since then lies within
    ``symmetry_position_tol`` and ``symmetry_angle_tol`` of it."""
    return checked_before([c for c in checked if c.contradicted], pose, odom, cfg)


def checked_before(
    checked: list[Checked], pose: FloatArray, odom: FloatArray, cfg: LocalizerConfig
) -> bool:
    """True when an earlier image of ``checked`` checked the hypothesis ``pose`` (3,) (as
    :func:`contradicted_before`, whatever it said)."""
    for c in checked:
        now = np.asarray(compose(c.pose, relative(c.odom, odom)), dtype=np.float64)
        if (
            math.hypot(now[0] - pose[0], now[1] - pose[1]) <= cfg.symmetry_position_tol
            and abs(float(angle_diff(now[2], pose[2]))) <= cfg.symmetry_angle_tol
        ):
            return True
    return False


def _listed(numbers: list[int]) -> str:
    """``hypothesis 3`` / ``hypotheses 2, 5 and 7`` (1-based numbers), for reasons."""
    if len(numbers) == 1:
        return f"hypothesis {numbers[0]}"
    return "hypotheses " + ", ".join(map(str, numbers[:-1])) + f" and {numbers[-1]}"


def _has_keyframes(ctx: Context) -> bool:
    """The visual map holds keyframes: the camera can check hypotheses (else a laser-only robot)."""
    return ctx.keyframes is not None and ctx.keyframes.keyframe_count() > 0


def _spacing(samples: FloatArray) -> float:
    """Largest distance [m] between consecutive poses of ``samples`` (M, 3) (0 for one)."""
    if samples.shape[0] < 2:
        return 0.0
    return float(np.max(np.hypot(*np.diff(samples[:, :2], axis=0).T)))


def _open_copies(ctx: Context, inp: Inputs, poses: FloatArray, fits: FloatArray) -> int:
    """How many of the hypotheses ``poses`` (K, 3) (aligned, best first, with ``fits`` (K,))
    to keep so that every rotated copy of the best (about a map symmetry or the known place
    there, within ``symmetry_position_tol`` and ``symmetry_angle_tol``) that the copy check
    would not rule out (:class:`~.copies.CopyRule`: the claim gate's floor, the map's slack)
    stays: that check (:func:`~.phases.copies_ambiguity`) would not let the best one be
    earned while such a copy fits, so the camera must choose. 0 when there is none."""
    cfg = ctx.config
    gate = ctx.gate
    if gate is None or not isinstance(inp.scan, LaserScan) or poses.shape[0] < 2:
        return 0
    copies = _copies_of(ctx, poses[0])
    if copies.shape[0] == 0:
        return 0
    scan = inp.scan
    floor = claim_floor(scan, gate) if cfg.copy_claim_floor else math.inf
    slack = cfg.copy_map_slack
    own_loose = gate.share_within(poses[0], scan, slack) if slack > 0.0 else 0.0
    keep = 0
    for i in range(1, poses.shape[0]):
        near = np.hypot(copies[:, 0] - poses[i, 0], copies[:, 1] - poses[i, 1])
        turn = np.abs(angle_diff(copies[:, 2], poses[i, 2]))
        if not np.any((near <= cfg.symmetry_position_tol) & (turn <= cfg.symmetry_angle_tol)):
            continue
        loose = None
        if slack > 0.0:
            loose = np.array([own_loose, gate.share_within(poses[i], scan, slack)])
        pair = CopyScores(np.array([fits[0], fits[i]]), loose, floor)
        if pair.open(cfg.copy_score_ratio):
            keep = i + 1
    return keep


def _copies_of(ctx: Context, pose: FloatArray) -> FloatArray:
    """The rotated copies (M, 3) of ``pose`` (3,) that the copy check weighs: about every
    map symmetry and about the known place whose disc holds the pose."""
    out = [
        rotated_copies(pose, s.centre, SymmetryOrder.finite(s.order))[1:]
        for s in ctx.map_symmetries
    ]
    place = known_place_at(pose, ctx.known_places, ctx.config.place_radius_factor)
    if place is not None:
        out.append(rotated_copies(pose, place.center, place.order)[1:])
    return np.concatenate(out) if out else np.zeros((0, 3))


def _align(ctx: Context, inp: Inputs, poses: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Each pose aligned to the map by the claim gate's matcher and the share of beams that
    then fit; without a gate, the pose scorer's scores of the poses as given."""
    gate = ctx.gate
    if gate is not None:
        scan = cast(LaserScan, inp.scan)
        out = np.empty_like(poses)
        fits = np.empty(poses.shape[0])
        for i in range(poses.shape[0]):
            pose, fit = gate.fit(poses[i], scan)
            out[i], fits[i] = pose, fit
        return out, fits
    if ctx.scorer is not None:
        return poses, np.asarray(ctx.scorer(poses, inp.scan), dtype=np.float64)
    return poses, np.ones(poses.shape[0])


def _distinct_fits(poses: FloatArray, fits: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Poses (best first) that aligned onto the same pose kept once, with their fits."""
    keep: list[int] = []
    for i in range(poses.shape[0]):
        p = poses[i]
        if not any(
            math.hypot(*(poses[j, :2] - p[:2])) < SAME_DISTANCE
            and abs(float(wrap_angle(poses[j, 2] - p[2]))) < SAME_ANGLE
            for j in keep
        ):
            keep.append(i)
    return poses[keep], fits[keep]


def _hypotheses(poses: FloatArray) -> tuple[Hypothesis, ...]:
    n = poses.shape[0]
    return tuple(Hypothesis(pose=p.copy(), weight=1.0 / n) for p in poses)


@dataclass(frozen=True)
class AxisVote:
    """One image's decided heading class along an axis: ``rotation`` [rad] the map-from-odometry
    rotation it implies (the camera's map heading minus the odometry heading, unchanged by
    turns in place and by driving), ``heading`` [rad] the odometry heading the image was
    taken at."""

    rotation: float
    heading: float

    def apart_from(self, other: AxisVote, turn: float) -> bool:
        """Whether the two images were taken at odometry headings at least ``turn`` [rad]
        apart (views of different keyframes, not the same view twice)."""
        return abs(float(angle_diff(self.heading, other.heading))) >= turn


@dataclass
class DecideHere:
    """Deciding from where the robot stands (see the module docstring).

    ``poses`` (K, 3) the hypotheses shown to the camera, at odometry pose ``odom0`` (None
    between views); ``views`` images asked for, at odometry headings ``seen`` [rad];
    ``waited`` scans without the image; ``turns`` turns in place made;
    ``turn_start`` / ``turn`` the odometry heading and angle [rad] of a turn under way;
    ``rest_after`` scans the other phases get once this one hands over or gives up
    (:class:`DecideRouter` reads it). ``back`` the axis being reported, when deciding here
    came from it (the estimates stay ``axis``, and nothing decided returns to it);
    ``classes`` the two heading classes of an axis family and ``labels`` (K,) the class of
    each pose shown, while the image is to decide the heading.
    """

    name: ClassVar[str] = "decide_here"
    why: str
    poses: FloatArray | None = None
    #: the share of beams each of :attr:`poses` explains (the laser's ranking of them)
    fits: FloatArray | None = None
    odom0: FloatArray | None = None
    views: int = 0
    seen: list[float] = field(default_factory=list)
    waited: int = 0
    turns: int = 0
    turn_start: float | None = None
    turn: float = 0.0
    rest_after: int = 0
    back: OnAxis | None = None
    classes: tuple[AxisClass, AxisClass] | None = None
    #: [m] how far each hypothesis shown to the camera stands for (half the spacing of the
    #: poses sampled along an axis; 0 for hypotheses the laser aligned one by one)
    reach: float = 0.0
    #: each image's decided heading class (:class:`AxisVote`), this episode's and those of
    #: earlier episodes since the last reset (:class:`DecideRouter` keeps them)
    axis_votes: list[AxisVote] = field(default_factory=list)
    labels: NDArray[np.int64] | None = None
    #: the survivors watched by the laser as the robot moves (no keyframes to show them to,
    #: or the camera decided nothing)
    watch: LaserWatch | None = None
    #: the watched survivors came from a complete search (the truth is among them): the
    #: leader is claimed; else (no camera, an open map) AMCL is reseeded at it to earn it
    watch_complete: bool = True
    #: what the images of this episode said about each hypothesis they checked
    checked: list[Checked] = field(default_factory=list)
    #: every hypothesis an image of this episode verified, whatever else it verified
    verified: list[Checked] = field(default_factory=list)
    #: why the camera is done here (its views used up, no keyframe in view): the laser's
    #: proposals go to the watch from then on; empty while the camera may still decide
    camera_done: str = ""
    #: a round map's centre (3,) in the odometry frame while driving to it before deciding
    #: (``LocalizerConfig.decide_round_reach``); True once this episode went there
    round_target: FloatArray | None = None
    centred: bool = False
    #: the least distance [m] to that centre so far, and scans since it last shrank by 2 cm
    round_best: float = math.inf
    round_stall: int = 0
    #: scans in a row that no pose explained (:data:`UNEXPLAINED_PATIENCE`)
    unexplained: int = 0

    def step(self, ctx: Context, inp: Inputs) -> Step:
        if self.watch is not None:
            return self._watching(ctx, inp, self.watch)
        if self.turn_start is not None:
            turned = float(angle_diff(inp.odom_pose[2], self.turn_start))
            remaining = float(angle_diff(self.turn, turned))
            if abs(remaining) > ctx.config.decide_turn_tolerance:
                return self._wait(
                    ctx,
                    inp,
                    Request(RequestKind.ROTATE, angle=remaining),
                    f"deciding here: turning to look elsewhere (view {self.views + 1})",
                ), self
            self.turn_start = None
        if self.round_target is not None:
            target = relative(inp.odom_pose, self.round_target)[:2]
            left = math.hypot(*target)
            self.waited += 1
            if left < self.round_best - 0.02:
                self.round_best, self.round_stall = left, 0
            self.round_stall += 1
            if (
                left > ctx.config.decide_round_reach
                and self.waited <= ROUND_PATIENCE
                and self.round_stall <= ROUND_STALL
            ):
                # at travelling speed: within decide_round_reach is enough, not millimetres
                request = Request(RequestKind.GO_TO, target=np.asarray(target))
                why = (
                    "deciding here: a round room: going to its centre first "
                    f"({math.hypot(*target):.1f} m away)"
                )
                return self._wait(ctx, inp, request, why), self
            self.round_target, self.waited = None, 0
        if self.poses is None:
            return self._propose(ctx, inp)
        if inp.image is None:
            self.waited += 1
            if self.waited > IMAGE_PATIENCE:
                return self._give_up(ctx, inp, "no image arrived")
            request = Request(RequestKind.CAPTURE_IMAGE)
            return self._wait(ctx, inp, request, "waiting for the image"), self
        return self._verify(ctx, inp, inp.image)

    def _wait(self, ctx: Context, inp: Inputs, request: Request, reason: str) -> Estimate:
        """A scan spent turning or waiting for the image: the axis when deciding from it."""
        if self.back is not None:
            return self._on_axis(ctx, inp, request, reason)
        return self._ask(inp, request, reason)

    # ------------------------------------------------------------------ the laser

    def _propose(self, ctx: Context, inp: Inputs) -> Step:
        cfg = ctx.config
        counts = ctx.record.decide
        counts.proposals += 1
        hyp = propose(ctx, inp)
        if hyp.survivors == 0:
            self.unexplained += 1
            why = hyp.reason or "no pose explains the scan"
            if self.unexplained > UNEXPLAINED_PATIENCE:
                return self._give_up(ctx, inp, why)
            hold = Request(RequestKind.ROTATE, angle=0.0)
            return self._wait(
                ctx,
                inp,
                hold,
                f"deciding here: {why} ({self.unexplained} of {UNEXPLAINED_PATIENCE} scans in "
                "a row); holding still for the next",
            ), self
        self.unexplained = 0
        if hyp.survivors == 1 and hyp.complete:
            counts.laser_single += 1
            single = f"{100 * hyp.fits[0]:.0f} % of beams fit, the next {self._next_fit(hyp)}"
            cov = cov_from_std(cfg.reseed_xy_std, cfg.reseed_theta_std)
            claimed = self._laser_claim(ctx, inp, hyp.poses[0], cov, single)
            if claimed is not None:
                return claimed
            return self._reseed(
                ctx, inp, hyp.poses[0], f"the laser alone leaves one pose ({single})"
            )
        poses = hyp.poses[: hyp.survivors]
        fits = hyp.fits[: hyp.survivors]
        pinned = pin_axis(ctx, inp, poses)
        if pinned is not None:
            ctx.notes.note_once(
                f"deciding here: {len(poses)} poses along an axis explain the scan, and the "
                "scan's ends pin one per heading class"
            )
            poses, fits = pinned
        found = None if pinned is not None else axis_classes(ctx, inp, poses)
        if found is not None:
            return self._axis(ctx, inp, found[1], len(poses))
        going = self._to_round_centre(ctx, inp, poses)
        if going is not None:
            return going
        keyframes = ctx.keyframes
        has_keyframes = _has_keyframes(ctx)
        if not has_keyframes:
            self.camera_done = "no keyframes to tell them apart"
        turn = None
        if keyframes is not None and not self.camera_done:
            turn = self._choose_view(ctx, inp, poses, keyframes)
        if self.camera_done:
            # the camera cannot decide here: the laser watches the survivors as the robot moves
            if len(poses) == 1 and not has_keyframes:
                counts.laser_seeded += 1
                return self._reseed(
                    ctx,
                    inp,
                    poses[0],
                    f"one pose explains the scan ({100 * fits[0]:.0f} % of beams), the search "
                    f"incomplete ({hyp.reason}) and no camera",
                )
            if self._can_watch(ctx, inp, hyp, has_keyframes):
                return self._watch(ctx, inp, poses, hyp)
            return self._give_up(
                ctx, inp, f"{len(poses)} poses explain the scan and {self.camera_done}"
            )
        if turn is not None:
            return turn
        self.poses, self.odom0, self.waited = poses.copy(), inp.odom_pose.copy(), 0
        self.fits = fits.copy()
        self.views += 1
        self.seen.append(float(inp.odom_pose[2]))
        ctx.note(
            f"deciding here: {len(poses)} poses explain the scan "
            f"({', '.join(f'{100 * f:.0f}' for f in fits)} % of beams); "
            f"image {self.views} of {cfg.decide_views} requested"
            + ("" if hyp.complete else f" (the search is incomplete: {hyp.reason})")
        )
        request = Request(RequestKind.CAPTURE_IMAGE)
        why = f"{len(poses)} poses explain the scan; image requested"
        return self._wait(ctx, inp, request, why), self

    def _to_round_centre(self, ctx: Context, inp: Inputs, poses: FloatArray) -> Step | None:
        """On a round map, survivors (K, 3) further than ``decide_round_reach`` from its
        centre: the drive there starts (once an episode; the centre carried by odometry from
        where the best survivor puts it) and this is its first step; else None."""
        gate = ctx.gate
        if gate is None or gate.rotation_centre is None or self.centred:
            return None
        centre = gate.rotation_centre
        if math.hypot(*(poses[0, :2] - centre)) <= ctx.config.decide_round_reach:
            return None
        self.centred, self.waited = True, 0
        in_robot = relative(poses[0], np.array([centre[0], centre[1], 0.0]))
        self.round_target = np.asarray(compose(inp.odom_pose, in_robot), dtype=np.float64)
        ctx.note(
            f"deciding here: {len(poses)} poses of a round room explain the scan, "
            f"{math.hypot(*(poses[0, :2] - centre)):.1f} m from its centre: going there first"
        )
        return self.step(ctx, inp)

    def _reseed(self, ctx: Context, inp: Inputs, pose: FloatArray, why: str) -> Step:
        """AMCL reseeded at ``pose`` (3,), the one pose the laser left, to be earned as any
        convergence of AMCL is (:class:`~.phases.Lost`: the copy checks and the claim gate)."""
        cfg = ctx.config
        cov = cov_from_std(cfg.reseed_xy_std, cfg.reseed_theta_std)
        ctx.tracker.initialize_pose(pose, cov)
        if ctx.gate is not None:
            ctx.gate.anchor(pose, cov, inp.odom_pose)
        why = f"{why}: AMCL reseeded there, pose to be earned"
        ctx.note(f"deciding here: {why}")
        self.rest_after = max(1, cfg.decide_rest // 3)
        return lost(why, inp.result), restart(ctx)

    def _laser_claim(
        self, ctx: Context, inp: Inputs, pose: FloatArray, cov: FloatArray, single: str
    ) -> Step | None:
        """The laser alone leaves one pose ``pose`` (3,) (known to ``cov`` (3, 3)): claimed at
        this scan when the claim gate confirms it and no rotated copy of it explains the scan
        about as well (the copy check every first claim passes); None to earn it through AMCL
        as before (no gate, a claim withheld or refused). A copy check that finds something
        returns its step (ambiguous, or to a symmetric place's centre), as on convergence.

        Waiting for AMCL to converge from the reseed added nothing the gate does not test
        (the same scan matcher, the same copy check) but ten scans or so, about a second.
        """
        gate = ctx.gate
        if gate is None or not isinstance(inp.scan, LaserScan):
            return None
        claim = gate.confirm(pose, cov, inp.scan)
        if claim.verdict is not Verdict.CLAIM or claim.pose is None:
            return None
        found = copies_ambiguity(ctx, inp, Lost.fresh(ctx.config), claim.pose)
        if found is not None:
            return found
        ctx.record.decide.laser_claimed += 1
        reason = f"decided here: the laser alone leaves one pose ({single}); pose set by the laser"
        return self._claimed(ctx, inp, claim, reason)

    def _axis(
        self, ctx: Context, inp: Inputs, classes: tuple[AxisClass, AxisClass], count: int
    ) -> Step:
        """The survivors are an axis family: renew the axis being reported when one class has
        its heading, else show both classes to the camera."""
        cfg = ctx.config
        back = self.back
        if back is not None:
            c = back.class_of(classes, SAME_CLASS)
            if c is not None:
                back.renew(classes[c], inp.odom_pose)
                # said once while it lasts (the estimate's reason gives the segment each scan)
                ctx.notes.note_once("deciding here: the laser proposes the axis again")
                self.rest_after = cfg.axis_recheck
                return back.estimate(cfg, back.headline()), back
            ctx.note("axis given up: the laser's axis no longer has the decided heading")
            self.back = None
        keyframes = ctx.keyframes
        if keyframes is None or keyframes.keyframe_count() == 0:
            return self._give_up(
                ctx, inp, f"{count} poses along an axis explain the scan and no keyframes"
            )
        shown = [c.fitted.samples(cfg.axis_spacing, cfg.axis_max_hypotheses) for c in classes]
        # the true pose lies anywhere between two samples: each sample's expected keyframes
        # reach half the spacing further (the view planner and the camera alike)
        reach = 0.5 * max(_spacing(s) for s in shown)
        turn = None
        if not self.camera_done:
            turn = self._choose_view(ctx, inp, np.vstack(shown), keyframes, reach)
        if self.camera_done:
            return self._give_up(
                ctx, inp, f"{count} poses along an axis explain the scan and {self.camera_done}"
            )
        if turn is not None:
            return turn
        self.poses = np.vstack(shown)
        self.labels = np.repeat(np.arange(2, dtype=np.int64), [len(s) for s in shown])
        self.classes = classes
        self.reach = reach
        self.odom0, self.waited = inp.odom_pose.copy(), 0
        self.views += 1
        self.seen.append(float(inp.odom_pose[2]))
        lengths = " and ".join(f"{c.fitted.length:.1f} m" for c in classes)
        ctx.note(
            f"deciding here: {count} poses explain the scan along an axis (heading known up to "
            f"a half turn, {lengths} along the two lines); {len(self.poses)} hypotheses along "
            f"both shown to the camera, image {self.views} of {cfg.decide_views} requested"
        )
        request = Request(RequestKind.CAPTURE_IMAGE)
        why = "poses along an axis explain the scan; image requested"
        return self._wait(ctx, inp, request, why), self

    def _choose_view(
        self,
        ctx: Context,
        inp: Inputs,
        poses: FloatArray,
        keyframes: KeyframeStore,
        reach: float = 0.0,
    ) -> Step | None:
        """None when the image is to be taken here; else the step that turns the robot to
        where more hypotheses of ``poses`` (K, 3) expect keyframes (or away from a heading
        already imaged; ``reach`` [m] as in :meth:`KeyframeStore.expected_counts`). When no
        heading left shows any a keyframe, the camera is done here (``camera_done`` says why)
        and None is returned."""
        cfg = ctx.config
        heading = float(inp.odom_pose[2])

        def expected(p: FloatArray) -> NDArray[np.int64]:
            return keyframes.expected_counts(p, reach)

        # look first where the hypotheses no image has checked yet expect keyframes: a
        # decision waits for them (see :meth:`_verify`)
        pending = np.array(
            [not checked_before(self.checked, p, inp.odom_pose, cfg) for p in poses], dtype=bool
        )
        plan = plan_turn(
            poses[pending] if 0 < np.count_nonzero(pending) < len(poses) else poses,
            expected,
            seen=[float(angle_diff(h, heading)) for h in self.seen],
            spacing=cfg.decide_turn,
            margin=cfg.decide_turn_tolerance,
        )
        if not plan.useful:
            where = "in any direction" if not self.seen else "in a direction not yet seen"
            self.camera_done = f"no keyframe to compare them with {where}"
            return None
        here = int(np.count_nonzero(expected(poses) > 0))
        seen_here = any(abs(float(angle_diff(h, heading))) <= cfg.decide_turn for h in self.seen)
        if seen_here or here < plan.covered:
            return self._turn_to(ctx, inp, poses, plan.turn, plan.covered)
        return None

    def _turn_to(
        self, ctx: Context, inp: Inputs, poses: FloatArray, turn: float, covered: int
    ) -> Step:
        """Turn in place by ``turn`` [rad], where ``covered`` hypotheses expect keyframes; the
        laser proposes again once there."""
        if self.turns >= TURNS_PER_VIEW * ctx.config.decide_views:
            return self._give_up(ctx, inp, f"{self.turns} turns without a view to compare")
        self.turns += 1
        ctx.record.decide.turns += 1
        self.poses, self.odom0 = None, None
        self.turn_start, self.turn = float(inp.odom_pose[2]), turn
        why = (
            f"deciding here: turning {math.degrees(turn):+.0f} deg to where {covered} of "
            f"{len(poses)} hypotheses expect keyframes"
        )
        ctx.note(why)
        request = Request(RequestKind.ROTATE, angle=turn)
        if self.back is not None:
            return self._on_axis(ctx, inp, request, why), self
        estimate = Estimate(
            status=Status.DECIDING, hypotheses=_hypotheses(poses), request=request, reason=why
        )
        return estimate, self

    # ------------------------------------------------------------------ the laser, moving

    @staticmethod
    def _can_watch(ctx: Context, inp: Inputs, hyp: Hypotheses, has_keyframes: bool) -> bool:
        """The laser may watch the survivors: the search is complete (the truth is among
        them) or there is no camera (an open map: the leader will only reseed AMCL,
        :meth:`_watched`), a claim gate aligns them, the scan is not judged symmetric and the
        best hypothesis is not in a known symmetric place (both the paper's case: the drive to
        the place's centre, where the camera decides against the visual map's places, has its
        turn after this path gives up)."""
        symmetric = bool(inp.verdict.symmetric) and inp.verdict.center is not None
        usable = ctx.gate is not None and isinstance(inp.scan, LaserScan)
        place = known_place_at(hyp.poses[0], ctx.known_places, ctx.config.place_radius_factor)
        searched = hyp.complete or not has_keyframes
        return searched and usable and not symmetric and place is None

    def _watch(self, ctx: Context, inp: Inputs, poses: FloatArray, hyp: Hypotheses) -> Step:
        """Several survivors and the camera cannot decide (no keyframes, none in view, or its
        views used up): watch them with the laser as the robot moves
        (:mod:`symloc.localizer.laser_watch`), from this scan on."""
        cfg = ctx.config
        ctx.record.decide.watched += 1
        self.watch_complete = hyp.complete
        self.watch = LaserWatch(
            poses=poses.copy(),
            odom=inp.odom_pose.copy(),
            slack=cfg.copy_map_slack,
            evidence=cfg.decide_watch_evidence,
        )
        ctx.note(
            f"deciding here: {len(poses)} poses explain the scan "
            f"({', '.join(f'{100 * f:.0f}' for f in hyp.fits[: len(poses)])} % of beams) and "
            f"{self.camera_done}: the laser watches them as the robot moves"
        )
        return self._watching(ctx, inp, self.watch)

    def _watching(self, ctx: Context, inp: Inputs, watch: LaserWatch) -> Step:
        """One scan of the watch: decided (the laser confirms the leader), given up, or the
        hypotheses reported as ambiguous."""
        cfg = ctx.config
        gate = ctx.gate
        assert gate is not None
        scan = cast(LaserScan, inp.scan)
        verdict = watch.step(gate, scan, inp.odom_pose)
        if verdict.decided and verdict.leader is not None:
            return self._watched(ctx, inp, watch, verdict)
        if verdict.leader is not None and watch.last_fits[verdict.leader] < cfg.decide_min_fit:
            self.watch = None
            return self._give_up(
                ctx, inp, "the laser's leading hypothesis no longer explains the scan"
            )
        idle = watch.learning(verdict)
        if idle:
            self.watch = None
            return self._give_up(
                ctx,
                inp,
                f"{len(watch.poses)} poses explain the scan, {self.camera_done}, and {idle}",
            )
        if verdict.views >= cfg.decide_watch_views:
            self.watch = None
            return self._give_up(
                ctx,
                inp,
                f"{len(watch.poses)} poses still explain the scans after {verdict.views} views "
                f"(least evidence {verdict.evidence:.2f} of {cfg.decide_watch_evidence:g}) and "
                f"{self.camera_done}",
            )
        why = (
            f"{len(watch.poses)} poses explain the scan and {self.camera_done}: the laser watches them"
            f" as the robot moves (view {verdict.views}, least evidence against a rival "
            f"{max(0.0, verdict.evidence):.2f} of {cfg.decide_watch_evidence:g})"
        )
        estimate = Estimate(
            status=Status.AMBIGUOUS, hypotheses=_hypotheses(watch.poses), reason=why
        )
        return estimate, self

    def _watched(self, ctx: Context, inp: Inputs, watch: LaserWatch, verdict: WatchVerdict) -> Step:
        """The laser's watch ruled every rival out: the laser confirms the leader and tracking
        starts there (the choice among the copies is made, as after a visual decision). After
        a search that could not be complete the truth may be none of them: AMCL is reseeded
        at the leader instead, and the pose earned as any convergence of AMCL is."""
        assert verdict.leader is not None
        cfg = ctx.config
        gate = ctx.gate
        assert gate is not None
        self.watch = None
        pose = watch.poses[verdict.leader]
        count = len(watch.poses)
        if not self.watch_complete:
            ctx.record.decide.laser_seeded += 1
            return self._reseed(
                ctx,
                inp,
                pose,
                f"hypothesis {verdict.leader + 1} of {count} led the laser's watch over "
                f"{verdict.views} views (least evidence against a rival {verdict.evidence:.2f}),"
                " the search incomplete and no camera",
            )
        cov = cov_from_std(cfg.decision_xy_std, cfg.decide_theta_std)
        claim = gate.confirm(pose, cov, cast(LaserScan, inp.scan))
        what = (
            f"hypothesis {verdict.leader + 1} of {count} singled out by the laser over "
            f"{verdict.views} views (least evidence against a rival {verdict.evidence:.2f})"
        )
        if claim.verdict is Verdict.WITHHELD and claim.pose is not None:
            return self._await_precision(ctx, inp, claim, what)
        if claim.verdict is not Verdict.CLAIM:
            ctx.record.decide.rejected += 1
            return self._give_up(ctx, inp, f"{what}, but the laser did not confirm it")
        assert claim.pose is not None
        assert claim.covariance is not None
        return self._claimed(ctx, inp, claim, f"decided here: {what}; pose set by the laser")

    @staticmethod
    def _next_fit(hyp: Hypotheses) -> str:
        return f"{100 * hyp.fits[1]:.0f} %" if hyp.fits.size > 1 else "none"

    # ------------------------------------------------------------------ the camera

    def _verify(self, ctx: Context, inp: Inputs, image: NDArray[np.uint8]) -> Step:
        assert self.poses is not None
        assert self.odom0 is not None
        assert ctx.keyframes is not None
        cfg = ctx.config
        counts = ctx.record.decide
        counts.images += 1
        moved = relative(self.odom0, inp.odom_pose)
        carried = np.asarray(compose(self.poses, moved), dtype=np.float64).reshape(-1, 3)
        centre = None if ctx.gate is None else ctx.gate.rotation_centre
        answer = ctx.keyframes.verify(carried, image, self.reach if self.classes else 0.0)
        ctx.record.last_camera_check = (carried, answer)
        if self.classes is not None and self.labels is not None:
            vote = vote_heading(carried, self.labels, answer, cfg.axis_min_inliers)
            if vote.winner is None:
                return self._look_elsewhere(
                    ctx, inp, f"image {self.views}: heading not decided: {vote.reason}"
                )
            heading = float(inp.odom_pose[2])
            now = AxisVote(float(angle_diff(vote.heading, heading)), heading)
            votes = self.axis_votes
            if any(
                abs(float(wrap_angle(v.rotation - now.rotation))) > 0.5 * math.pi for v in votes
            ):
                votes.clear()
                return self._look_elsewhere(
                    ctx, inp, f"image {self.views}: the views disagree on the heading class"
                )
            votes.append(now)
            apart = cfg.decide_turn - cfg.decide_turn_tolerance
            agree = 1 + sum(1 for v in votes[:-1] if v.apart_from(now, apart))
            if agree < cfg.axis_views:
                return self._look_elsewhere(
                    ctx,
                    inp,
                    f"image {self.views}: {vote.reason}; {agree} of {cfg.axis_views} views "
                    "agree so far",
                )
            votes.clear()
            self.rest_after = cfg.axis_recheck
            return enter_axis(ctx, inp, self.classes[vote.winner], self.odom0, vote.reason)
        cov = cov_from_std(cfg.decision_xy_std, cfg.decide_theta_std)
        # verified before this image, carried to now: a pose the camera vouched for once
        # is not ruled out by a later view that fails to see it
        seen = checked_by(carried, inp.odom_pose, answer, centre)
        before = list(self.verified)
        self.verified.extend(c for c in seen if not c.contradicted)
        index, pose_or_none, verdict = answer.index, answer.pose, answer.reason
        if (index is None or centre is not None) and ctx.gate is not None:
            # a round map always: its fits measure members of the room's family, wherever
            # they are (verified_together)
            together = (
                one_pose_verified(ctx.gate, inp.scan, carried, answer, cov)
                if isinstance(inp.scan, LaserScan)
                else None
            )
            index, pose_or_none, verdict = (
                (together.index, together.pose, together.reason)
                if together is not None
                else (None, None, answer.reason)
            )
        if index is None or pose_or_none is None:
            return self._look_elsewhere(ctx, inp, f"image {self.views}: {verdict}")
        if self.classes is None:
            self.checked.extend(seen)
            fits = self.fits
            unchecked = [
                i + 1
                for i, c in enumerate(answer.checks)
                if c.status == "unknown"
                and not contradicted_before(self.checked, carried[i], inp.odom_pose, cfg)
                and (fits is None or fits[i] >= fits[index])
            ]
            if unchecked:
                # every hypothesis shown survived the laser; one no image of this episode
                # could check (no keyframe looks where it says the camera looks) may be the
                # truth, and the verified one a look-alike (a repeated texture). Between the
                # two only the laser has spoken: the camera cannot overrule it in favour of
                # a pose the laser ranks no higher than the unchecked one
                return self._look_elsewhere(
                    ctx,
                    inp,
                    f"image {self.views}: hypothesis {index + 1} verified, but no image could "
                    f"check {_listed(unchecked)}, which the laser ranks at least as high",
                )
            also = (
                _other_members(before, pose_or_none, inp.odom_pose, answer.heading_tolerance)
                if centre is not None
                else [
                    j + 1
                    for j in range(carried.shape[0])
                    if j != index and checked_before(before, carried[j], inp.odom_pose, cfg)
                ]
            )
            if also:
                # the camera's views disagree: an earlier one verified another hypothesis
                # (keyframes that look alike from both, a short corridor's two ends); the
                # view that verifies one alone may be the look-alike
                return self._look_elsewhere(
                    ctx,
                    inp,
                    f"image {self.views}: hypothesis {index + 1} verified, but an earlier "
                    + (
                        f"image verified {len(also)} other member(s) of the round room's family"
                        if centre is not None
                        else f"image verified {_listed(also)} too"
                    ),
                )
        counts.verified += 1
        pose = np.asarray(pose_or_none, dtype=np.float64)
        if self.back is not None and abs(float(angle_diff(pose[2], self.back.heading))) > (
            0.5 * math.pi
        ):
            ctx.note("axis given up: the camera now verifies a pose facing against it")
            self.back = None
            return self._look_elsewhere(
                ctx,
                inp,
                f"image {self.views}: hypothesis {index + 1} verified, but it faces "
                "against the axis decided before: neither is trusted",
            )
        gate = ctx.gate
        if centre is not None:
            # a round map: the laser cannot set the heading, so the camera's own measurement
            # of it (planar motion against the keyframes the decided member should be
            # seeing) is what the claim's heading rests on
            again = ctx.keyframes.verify(
                pose.reshape(1, 3), image, refine=True, round_centre=centre
            )
            if again.index != 0 or not math.isfinite(again.heading_std):
                # the coarse heading (decide_theta_std) can never be claimed in a round room,
                # and once AMCL is reseeded on it nothing there sharpens it: another view
                # may measure it (dev seeds 2-3: half the decisions at the centre ended so)
                return self._look_elsewhere(
                    ctx,
                    inp,
                    f"image {self.views}: hypothesis {index + 1} verified, but its heading "
                    "was not measured again ("
                    + (
                        "the planar-motion fits disagree)"
                        if again.index == 0
                        else f"the decided member alone: {again.reason})"
                    ),
                )
            pose = np.array([pose[0], pose[1], again.refined_heading])
            cov = cov_from_std(cfg.decision_xy_std, again.heading_std)
        claim = None
        if gate is not None:
            claim = gate.confirm(pose, cov, cast(LaserScan, inp.scan))
            if claim.verdict is Verdict.WITHHELD and claim.pose is not None:
                what = f"hypothesis {index + 1} of {len(carried)} verified by the camera"
                return self._await_precision(ctx, inp, claim, what)
            if claim.verdict is not Verdict.CLAIM:
                counts.rejected += 1
                return self._look_elsewhere(
                    ctx,
                    inp,
                    f"image {self.views}: hypothesis {index + 1} verified, but the laser "
                    f"did not confirm it ({claim.reason})",
                )
        reason = (
            f"decided here: hypothesis {index + 1} of {len(carried)} verified by the "
            f"camera ({verdict}); pose set by the laser"
        )
        if claim is not None:
            return self._claimed(ctx, inp, claim, reason)
        return self._published(ctx, inp, pose, cov, reason)

    def _claimed(self, ctx: Context, inp: Inputs, claim: Claim, reason: str) -> Step:
        """The laser claims a decided pose: AMCL is reseeded there, the claim chain starts
        at it (no copy check: the choice among copies is made) and it is published now."""
        gate = ctx.gate
        assert gate is not None
        assert claim.pose is not None
        assert claim.covariance is not None
        gate.anchor(claim.pose, claim.covariance, inp.odom_pose)
        gate.confirmed(claim, inp.odom_pose)
        return self._published(ctx, inp, claim.pose, claim.covariance, reason)

    @staticmethod
    def _published(
        ctx: Context, inp: Inputs, pose: FloatArray, cov: FloatArray, reason: str
    ) -> Step:
        """A decided pose (3,) with its covariance (3, 3) published now: AMCL reseeded there,
        tracking from this scan."""
        ctx.record.particles_before_decision = inp.result.particles
        reseed_tracker(ctx, pose, cov)
        ctx.record.decide.claimed += 1
        ctx.note(reason + "; AMCL reseeded")
        estimate = Estimate(
            status=Status.TRACKING,
            pose=pose,
            covariance=cov,
            hypotheses=(Hypothesis(pose=pose, weight=1.0),),
            reason=reason,
        )
        return estimate, Tracking(restart(ctx))

    def _await_precision(self, ctx: Context, inp: Inputs, claim: Claim, what: str) -> Step:
        """The camera chose a hypothesis and the laser fits it, but not yet precisely enough
        to claim: AMCL is reseeded there and the pose becomes the claim chain's start (its
        copy is chosen; :meth:`ClaimGate.step` publishes it once a scan confirms it with the
        gate's precision). Nothing is published at this scan."""
        gate = ctx.gate
        assert gate is not None
        assert claim.pose is not None
        assert claim.covariance is not None
        pose, cov = claim.pose, claim.covariance
        reseed_tracker(ctx, pose, cov)
        gate.anchor(pose, cov, inp.odom_pose)
        gate.confirmed(claim, inp.odom_pose)
        ctx.record.decide.withheld += 1
        why = (
            f"decided here: {what}; the "
            f"laser fits it but {claim.reason.removeprefix('claim withheld: ')}: AMCL reseeded, "
            "pose published once a scan confirms it"
        )
        ctx.note(why)
        estimate = Estimate(
            status=Status.AMBIGUOUS, hypotheses=(Hypothesis(pose=pose, weight=1.0),), reason=why
        )
        return estimate, Tracking(restart(ctx))

    def _look_elsewhere(self, ctx: Context, inp: Inputs, why: str) -> Step:
        """This view decided nothing: the laser proposes again and the view planner turns
        the robot to a heading not yet imaged (or the path gives up)."""
        ctx.note(f"deciding here: {why}")
        self.poses, self.odom0, self.classes, self.labels = None, None, None, None
        self.reach, self.fits = 0.0, None
        if self.views >= ctx.config.decide_views:
            # the camera is done: the laser proposes once more and watches the survivors as
            # the robot moves (or the path gives up)
            self.camera_done = f"no hypothesis verified in {self.views} views ({why})"
        return self._propose(ctx, inp)

    # ------------------------------------------------------------------ outcomes

    def _ask(self, inp: Inputs, request: Request, reason: str) -> Estimate:
        shown = self.poses
        return Estimate(
            status=Status.DECIDING,
            hypotheses=inp.result.hypotheses if shown is None else _hypotheses(shown),
            request=request,
            reason=reason,
        )

    def _on_axis(self, ctx: Context, inp: Inputs, request: Request, reason: str) -> Estimate:
        """While deciding here from the axis: the axis, carried by odometry, with the request
        (the heading is still known)."""
        back = self.back
        assert back is not None
        back.carry(ctx, inp.odom_pose)
        return back.report(ctx, inp, f"{back.headline()}; {reason}", request)

    def _give_up(self, ctx: Context, inp: Inputs, why: str) -> Step:
        ctx.record.decide.gave_up += 1
        reason = f"not decided here: {why}"
        ctx.note(reason)
        if self.back is not None:
            self.rest_after = ctx.config.axis_recheck
            back = self.back
            back.carry(ctx, inp.odom_pose)
            return back.report(ctx, inp, f"{back.headline()}; {reason}"), back
        cfg = ctx.config
        self.rest_after = cfg.decide_rest if _has_keyframes(ctx) else cfg.decide_rest_no_camera
        return lost(reason, inp.result), restart(ctx)


@dataclass
class DecideRouter:
    """Sends the localizer to :class:`DecideHere` whenever the pose is not earned: before a
    scan goes to :class:`~.phases.Lost`, to a trip to the centre that has not started, or to
    the axis (:class:`~.axis_phase.OnAxis`, which deciding here comes back to); not for
    ``rest`` scans after it handed over or gave up (the other phases' turn).

    ``axis_votes`` the heading classes images decided along an axis, kept from one episode to
    the next until the axis is entered, two disagree, or :meth:`reset`: in a long corridor
    most views verify nothing, and an episode of four views often holds one strong vote
    (dev corridor_long#0: 220 inliers against 0 for the half-turned class), which the next
    episode's would otherwise never meet."""

    rest: int = 0
    axis_votes: list[AxisVote] = field(default_factory=list)

    def route(self, ctx: Context, inp: Inputs, phase: Phase) -> Phase:
        """The phase that takes this scan."""
        if isinstance(phase, DecideHere):
            return phase
        if self.rest > 0:
            self.rest -= 1
            return phase
        if isinstance(phase, OnAxis):
            ctx.record.decide.entered += 1
            return DecideHere(
                why="on the axis, pose not earned", back=phase, axis_votes=self.axis_votes
            )
        if isinstance(phase, Lost) or (isinstance(phase, Centering) and phase.updates == 0):
            ctx.record.decide.entered += 1
            return DecideHere(why=f"pose not earned ({phase.name})", axis_votes=self.axis_votes)
        return phase

    def after(self, before: Phase, after: Phase) -> None:
        """Note the transition ``before`` -> ``after`` (a hand-over starts the rest)."""
        if isinstance(before, DecideHere) and not isinstance(after, DecideHere):
            self.rest = before.rest_after

    def reset(self) -> None:
        """Start-up, a kidnapping or an operator's pose: decide here at once when lost, with
        no earlier image's vote (the odometry they were taken on no longer relates to the
        map as it did)."""
        self.rest = 0
        self.axis_votes.clear()
