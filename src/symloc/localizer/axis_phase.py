"""Heading known, position along the axis not: the localizer's ``axis`` state.

In a long corridor the laser's hypotheses form an axis family (:mod:`symloc.localizer.axis`):
two heading classes, ``theta`` and ``theta + pi``, each a line of poses. Deciding here
(:mod:`symloc.localizer.decide_here`) shows both lines to the camera; when the image decides
the heading class (:mod:`symloc.localizer.axis_heading`) the localizer enters :class:`OnAxis`
and reports status ``axis``: the middle of the class' segment with the decided heading and a
covariance as long as the segment (:class:`~symloc.localizer.types.AxisPose`). Nothing is
claimed: the pose is not published as tracking, and it is not AMCL's.

:func:`axis_classes` turns the laser's hypotheses into the two classes' segments: the family's
line, swept by the pose scorer over the whole map to find where the scan fits (the search
lists only a few dozen of the poses along a corridor; the scan must fit all along the stretch,
``axis_continuity``, else the poses are discrete copies, such as between repeated pillars,
which the decide path's camera tells apart one by one), and lengthened by
``axis_open_reach`` at an end where the line runs on into space the map does not cover (a
mapping trip that stopped short of the corridor's end: the robot may stand there).

Each scan :class:`OnAxis`

1. runs the normal path first (:class:`~symloc.localizer.phases.Lost`'s step; AMCL was
   reseeded along the segment with the decided heading): when it leaves the lost phase (a pose
   earned, the drive to a symmetric place's centre) it takes over at once, so the axis never
   blocks it;
2. carries the segment by odometry (every pose on it has the same heading, so all move alike)
   and lengthens it by ``axis_odometry`` of the distance travelled at each end; the heading's
   std grows with the turning since the laser last confirmed it, by the robot's rotation error
   (the claim gate's ``alphas``), and past the gate's heading bound nothing is reported until a
   scan confirms it (:meth:`OnAxis.report`: on the heavy sensors, whose slip loses up to 30 %
   of a turn, axis headings carried through turns were published 5.5-7.6 deg off);
3. lets the laser check the heading: the class' reference pose (where the scan fitted),
   carried by odometry, is aligned to the map; fitting with the decided heading it becomes the
   new reference (its heading and its place across the corridor; along the corridor the laser
   cannot tell, and odometry's position is kept); fitting with another heading contradicts the
   axis (given up at once); not fitting at all for ``axis_patience`` scans in a row (the robot
   left the mapped part) gives it up.

Every ``axis_recheck`` scans :class:`~symloc.localizer.decide_here.DecideRouter` sends it to
deciding here again with this phase as the one to come back to: the laser proposes anew; an
axis family with the decided heading renews the segment without an image; anything else (an
end, a door in view) goes to the camera as always, and a pose verified there is claimed
through the claim gate (unless its heading contradicts the axis'). Nothing decided: back here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar, cast

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import compose, relative, rotation_matrix, wrap_angle
from symloc.scan import LaserScan

from .axis import (
    AxisFamily,
    AxisSegment,
    axis_covariance,
    axis_family,
    line_reach,
    map_corners,
    runs_out,
    sweep,
)
from .config import LocalizerConfig
from .context import Context, Inputs, lost, reseed_tracker
from .phases import Lost, Step, restart
from .types import AxisPose, Estimate, Hypothesis, Request, Status

__all__ = ["AxisClass", "OnAxis", "axis_classes", "enter_axis", "two_class_family"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class AxisClass:
    """One heading class of an axis family, where the robot may stand.

    ``fitted`` the stretch of the class' line where the scan fits the map (the camera's
    hypotheses are taken there); ``segment`` that stretch lengthened into unmapped space at
    ``open_ends`` of its ends (where the robot may be); ``reference`` (3,) the class'
    best-fitting hypothesis (aligned by the laser); ``across_std`` [m] the std across the line:
    how far its hypotheses scatter about it (at least ``axis_across_std``), with the sideways
    error a line direction off by ``axis_line_std`` makes at the segment's far end."""

    fitted: AxisSegment
    segment: AxisSegment
    reference: FloatArray
    open_ends: int
    across_std: float


def two_class_family(cfg: LocalizerConfig, poses: FloatArray) -> AxisFamily | None:
    """The axis family of ``poses`` (K, 3) under ``cfg``'s ``axis_*`` bounds when both its
    heading classes hold hypotheses; else None."""
    family = axis_family(
        poses,
        max_spread=cfg.axis_max_spread,
        max_heading_spread=cfg.axis_heading_spread,
        min_length=cfg.axis_min_length,
    )
    if family is None or family.count(0) == 0 or family.count(1) == 0:
        return None
    return family


def axis_classes(
    ctx: Context, inp: Inputs, poses: FloatArray
) -> tuple[AxisFamily, tuple[AxisClass, AxisClass]] | None:
    """The axis family of the laser's hypotheses ``poses`` (K, 3) (best first) with both its
    classes' extents, or None (not an axis family, or one class missing: the laser's list
    then says nothing about the half-turned heading, and the camera has nothing to compare)."""
    cfg = ctx.config
    family = two_class_family(cfg, poses)
    if family is None:
        return None
    scan = inp.scan
    scorer = ctx.scorer
    out: list[AxisClass] = []
    for c in (0, 1):
        seg = family.segment(c)
        # without the map, the line is swept as far as an unmapped stretch may reach
        lo, hi = seg.lo - cfg.axis_open_reach, seg.hi + cfg.axis_open_reach
        if ctx.grid is not None:
            lo, hi = line_reach(seg, map_corners(ctx.grid))
        if scorer is not None:
            found = sweep(
                lambda p: np.asarray(scorer(p, scan), dtype=np.float64),
                seg,
                lo,
                hi,
                ratio=cfg.axis_sweep_ratio,
            )
            # repeated features along a line (pillars) leave gaps: those poses are told
            # apart one by one, by the camera as anywhere else
            if found is None or found[1] < cfg.axis_continuity:
                return None
            swept = found[0]
            # the laser's own hypotheses explain the scan whatever the scorer says
            seg = replace(swept, lo=min(swept.lo, seg.lo), hi=max(swept.hi, seg.hi))
        fitted, opened = seg, 0
        if ctx.grid is not None:
            if runs_out(seg, ctx.grid, seg.lo, -1):
                seg, opened = replace(seg, lo=lo - cfg.axis_open_reach), opened + 1
            if runs_out(seg, ctx.grid, seg.hi, +1):
                seg, opened = replace(seg, hi=hi + cfg.axis_open_reach), opened + 1
        mine = np.flatnonzero(family.classes == c)
        reference = np.asarray(poses[mine[0]], dtype=np.float64).copy()
        # the line's direction is fitted where the scan fits; far from there a small error of
        # it (a map bends a little over its length) moves the line sideways
        middle = 0.5 * (fitted.lo + fitted.hi)
        reach = max(abs(seg.lo - middle), abs(seg.hi - middle))
        across = math.hypot(max(cfg.axis_across_std, family.spread), cfg.axis_line_std * reach)
        out.append(AxisClass(fitted, seg, reference, opened, across))
    return family, (out[0], out[1])


def enter_axis(
    ctx: Context, inp: Inputs, chosen: AxisClass, odom_then: FloatArray, why: str
) -> Step:
    """The camera decided ``chosen``'s heading (the class as the laser saw it at odometry pose
    ``odom_then`` (3,)): AMCL is reseeded along its segment, carried to this scan, with that
    heading, and the localizer reports the axis (:class:`OnAxis`)."""
    cfg = ctx.config
    phase = OnAxis(
        segment=chosen.segment,
        reference=chosen.reference.copy(),
        odom=np.asarray(odom_then, dtype=np.float64).copy(),
        open_ends=chosen.open_ends,
        across_std=chosen.across_std,
        lost=Lost.fresh(cfg),
        why=why,
    )
    phase.carry(ctx, inp.odom_pose)
    reseed_tracker(ctx, phase.segment.middle(), phase.covariance(cfg))
    ctx.record.decide.axis += 1
    ctx.note(
        f"axis: {why}; the position along the axis is not known ({phase.describe()}): "
        "AMCL reseeded along it, nothing claimed"
    )
    return phase.estimate(cfg, phase.headline()), phase


@dataclass
class OnAxis:
    """Heading known, position along the axis not (see the module docstring).

    ``segment`` where the robot may stand, at odometry pose ``odom``; ``reference`` (3,) the
    pose on the class' line where the scan last fitted (carried with the segment);
    ``open_ends`` ends lengthened into unmapped space; ``across_std`` [m] the spread across
    the line; ``lost`` the normal path's counters (its step runs first); ``misses`` scans in a
    row at which the laser did not confirm the axis; ``why`` how the heading was decided;
    ``turned`` [rad] the odometry's turning since the laser last confirmed the heading.
    """

    name: ClassVar[str] = "axis"
    segment: AxisSegment
    reference: FloatArray
    odom: FloatArray
    open_ends: int
    across_std: float
    lost: Lost
    why: str
    misses: int = 0
    turned: float = 0.0

    @property
    def heading(self) -> float:
        """The decided heading [rad] (map frame)."""
        return self.segment.heading

    def heading_std(self, ctx: Context) -> float:
        """The heading's std [rad]: ``axis_theta_std``, grown by the robot's rotation error
        (the claim gate's ``alphas[0]``) times the turning the laser has not confirmed, the
        whole turn's error counted together as a slip episode loses it (at least what
        :func:`~symloc.mcl.motion_model.carry_by_odometry` gives for that turning, which
        splits it in two rotations; the heading drift per metre, ``alphas[1]``, is left out)."""
        a1 = ctx.gate.alphas[0] if ctx.gate is not None else 0.0
        return math.sqrt(ctx.config.axis_theta_std**2 + a1 * self.turned**2)

    def step(self, ctx: Context, inp: Inputs) -> Step:
        estimate, after = self.lost.step(ctx, inp)
        if after is not self.lost or estimate.status is Status.TRACKING:
            ctx.note(f"axis left: the normal path takes over ({estimate.reason})")
            return estimate, after
        self.carry(ctx, inp.odom_pose)
        trouble = self.check(ctx, inp)
        if trouble is not None:
            ctx.note(f"axis given up: {trouble}")
            return lost(f"axis given up: {trouble}", inp.result), restart(ctx)
        return self.report(ctx, inp, self.headline()), self

    # ------------------------------------------------------------------ odometry, laser

    def carry(self, ctx: Context, odom_pose: FloatArray) -> None:
        """Move the segment and the reference by the odometry since ``odom``; the segment
        lengthens by ``axis_odometry`` of the distance at each end."""
        odom = np.asarray(odom_pose, dtype=np.float64)
        delta = np.asarray(relative(self.odom, odom), dtype=np.float64)
        seg = self.segment
        shift = rotation_matrix(seg.heading) @ delta[:2]
        pad = ctx.config.axis_odometry * float(np.hypot(delta[0], delta[1]))
        self.segment = AxisSegment(
            seg.point + shift,
            seg.unit,
            float(wrap_angle(seg.heading + delta[2])),
            seg.lo - pad,
            seg.hi + pad,
        )
        self.reference = np.asarray(compose(self.reference, delta), dtype=np.float64)
        self.odom = odom.copy()
        self.turned += abs(float(delta[2]))

    def check(self, ctx: Context, inp: Inputs) -> str | None:
        """The laser's check of the heading (see the module docstring, step 3): None while
        the axis holds, else why it is given up."""
        gate = ctx.gate
        cfg = ctx.config
        if gate is None:
            return None
        aligned, fit = gate.fit(self.reference, cast(LaserScan, inp.scan))
        if fit < cfg.decide_min_fit:
            self.misses += 1
            if self.misses > cfg.axis_patience:
                return (
                    f"the scan has not fitted the axis for {self.misses} scans "
                    "(the robot left the mapped part, or was carried off)"
                )
            return None
        turned = float(wrap_angle(aligned[2] - self.reference[2]))
        moved = (aligned[:2] - self.reference[:2]) @ self.segment.normal
        if abs(turned) > cfg.axis_heading_spread or abs(moved) > cfg.axis_max_spread:
            return (
                f"the scan fits {math.degrees(turned):+.0f} deg / {100 * moved:+.0f} cm from the "
                "axis' heading and line (carried off?)"
            )
        self.misses = 0
        self.turned = 0.0
        across = moved * self.segment.normal
        self.reference = np.array(
            [self.reference[0] + across[0], self.reference[1] + across[1], aligned[2]]
        )
        seg = self.segment
        self.segment = AxisSegment(seg.point + across, seg.unit, float(aligned[2]), seg.lo, seg.hi)
        return None

    def renew(self, chosen: AxisClass, odom_pose: FloatArray) -> None:
        """The laser proposed the axis again with this heading: its segment replaces the one
        carried (the laser's extent now, not the odometry's)."""
        self.segment = chosen.segment
        self.reference = chosen.reference.copy()
        self.open_ends = chosen.open_ends
        self.across_std = chosen.across_std
        self.odom = np.asarray(odom_pose, dtype=np.float64).copy()
        self.misses = 0
        self.turned = 0.0

    def class_of(self, classes: tuple[AxisClass, AxisClass], tolerance: float) -> int | None:
        """Which of ``classes`` has this axis' heading (within ``tolerance`` [rad]), if any."""
        for c, cls in enumerate(classes):
            if abs(float(wrap_angle(cls.segment.heading - self.heading))) <= tolerance:
                return c
        return None

    # ------------------------------------------------------------------ output

    def covariance(self, cfg: LocalizerConfig, theta_std: float | None = None) -> FloatArray:
        """The covariance (3, 3) of the axis estimate (:func:`axis_covariance`), its heading
        std ``theta_std`` [rad] (default ``axis_theta_std``)."""
        theta = cfg.axis_theta_std if theta_std is None else theta_std
        return axis_covariance(self.segment, self.across_std, theta)

    def headline(self) -> str:
        """The estimate's reason, before the segment's description."""
        return f"heading decided, position along the axis not: {self.why}"

    def describe(self) -> str:
        """The segment in words (its length, and whether it runs into unmapped space)."""
        opened = (
            ""
            if self.open_ends == 0
            else f", {self.open_ends} end(s) running on into unmapped space"
        )
        return f"segment {self.segment.length:.1f} m long{opened}"

    def report(
        self, ctx: Context, inp: Inputs, reason: str, request: Request | None = None
    ) -> Estimate:
        """The axis estimate (:meth:`estimate`, its heading std :meth:`heading_std`) while
        the heading is known to the claim gate's bound; past it (a turn the laser has not
        followed: deciding here turns to look elsewhere, or a fast turn skews the scans) the
        heading is odometry's alone, and nothing is reported (status ``deciding`` with
        ``request``, else ``lost``) until a scan confirms it: heavy slip loses up to 30 % of a
        turn."""
        std = self.heading_std(ctx)
        bound = ctx.gate.config.max_std_theta if ctx.gate is not None else math.inf
        if std <= bound:
            return self.estimate(ctx.config, reason, request, theta_std=std)
        return Estimate(
            status=Status.LOST if request is None else Status.DECIDING,
            hypotheses=inp.result.hypotheses,
            request=request,
            reason=(
                f"{reason}; axis held: the heading carried {math.degrees(self.turned):.0f} deg"
                f" through a turn the laser has not confirmed (std {math.degrees(std):.2f} deg,"
                f" at most {math.degrees(bound):.2f}): reported again once a scan confirms it"
            ),
        )

    def estimate(
        self,
        cfg: LocalizerConfig,
        reason: str,
        request: Request | None = None,
        theta_std: float | None = None,
    ) -> Estimate:
        """Status ``axis``: the segment's middle with the decided heading, its covariance
        (heading std ``theta_std``, default ``axis_theta_std``), the segment's ends as the
        hypotheses (for display)."""
        seg = self.segment
        ends = seg.at(np.array([seg.lo, seg.hi]))
        axis = AxisPose(
            pose=seg.middle(),
            covariance=self.covariance(cfg, theta_std),
            ends=seg.ends,
            open_ends=self.open_ends,
        )
        return Estimate(
            status=Status.AXIS,
            hypotheses=tuple(Hypothesis(pose=p, weight=0.5) for p in ends),
            request=request,
            reason=f"{reason} ({self.describe()})",
            axis=axis,
        )
