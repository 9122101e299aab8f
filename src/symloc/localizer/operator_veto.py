"""The camera's veto over the operator's choice among the map's copies.

An operator's initial pose (RViz's 2D Pose Estimate) chooses among a symmetric map's rotated
copies, so its first claim skips the copy check that every other first claim passes
(:func:`~symloc.localizer.phases.copies_ambiguity`). That choice is carried by odometry until
the laser is precise enough to claim, which in a large room or on poor wheels takes many
seconds, the carried pose growing a metre wide. A robot carried off meanwhile to where a copy
of its pose stands (a kidnapping onto the copy) changes nothing the laser or the odometry
sees, and would be published on the wrong copy: the bench's heavy regime did so once in 280
trials (rhombus#1000000, trial 3: claimed 4.2 m and 180 deg off, 9 s after the kidnapping).

So before that first claim, where a rotated copy explains the scan about as well and the
visual map has keyframes, one image is asked for. If it verifies a copy with margin
(:meth:`~symloc.localizer.types.KeyframeStore.verify`), the operator's choice is not believed
and the copies are decided as any others are. An image that verifies the operator's pose or
cannot tell leaves the choice standing (the camera vetoes; it need not confirm), and so does a
camera that sends no image within ``LocalizerConfig.operator_image_wait`` scans.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.symmetry.order import SymmetryOrder

from .context import Context, Inputs
from .copies import CopiesKind, copies_verdict, known_place_at, rotated_copies

__all__ = ["OperatorVeto", "Veto", "VetoKind", "explaining_copies"]

FloatArray = NDArray[np.float64]


class VetoKind(enum.Enum):
    """What the camera says of the operator's choice at one scan."""

    STANDS = "stands"  # claim the pose: no copy to fear, or the camera did not veto it
    LOOK = "look"  # hold the claim: an image is asked for
    VETOED = "vetoed"  # the camera verified a copy: the operator's choice is not believed


@dataclass(frozen=True)
class Veto:
    """:meth:`OperatorVeto.judge`'s answer and, for a veto, why in words."""

    kind: VetoKind
    reason: str = ""


def explaining_copies(ctx: Context, inp: Inputs, pose: FloatArray) -> FloatArray:
    """The rotated copies of ``pose`` (3,) (about a known symmetric place's centre and the
    map's symmetries, the pose itself left out) that explain the scan about as well as the
    pose, or better, as :func:`~symloc.localizer.phases.copies_ambiguity` judges them:
    ``(k, 3)``, ``k`` 0 when none does."""
    cfg = ctx.config

    def explain(centre: FloatArray, order: SymmetryOrder) -> CopiesKind:
        return copies_verdict(
            pose,
            centre,
            order,
            inp.scan,
            gate=ctx.gate,
            scorer=ctx.scorer,
            ratio=cfg.copy_score_ratio,
            floor=cfg.copy_claim_floor,
            slack=cfg.copy_map_slack,
        ).kind

    found: list[FloatArray] = []
    place = known_place_at(pose, ctx.known_places, cfg.place_radius_factor)
    if place is not None and explain(place.center, place.order) is not CopiesKind.UNIQUE:
        found.append(rotated_copies(pose, place.center, place.order)[1:])
    for sym in ctx.map_symmetries:
        order = SymmetryOrder.finite(sym.order)
        if explain(sym.centre, order) is not CopiesKind.UNIQUE:
            found.append(rotated_copies(pose, sym.centre, order)[1:])
    return np.concatenate(found) if found else np.zeros((0, 3))


@dataclass
class OperatorVeto:
    """Asks the camera, once, whether the operator's pose is a copy of where the robot stands.

    ``asked`` counts the scans an image has been asked for without one arriving; ``done`` is
    set once the choice was judged (it is judged once per operator's pose).
    """

    asked: int = 0
    done: bool = False

    def judge(self, ctx: Context, inp: Inputs, pose: FloatArray) -> Veto:
        """The camera's word on claiming ``pose`` (3,), the operator's pose as the laser
        confirmed it at this scan."""
        if self.done or ctx.keyframes is None:
            return Veto(VetoKind.STANDS)
        if inp.image is None:
            if self.asked >= ctx.config.operator_image_wait:
                self.done = True
                ctx.note(
                    f"no image in {self.asked} scans: the operator's choice among the map's "
                    "copies stands unchecked"
                )
                return Veto(VetoKind.STANDS)
            if not explaining_copies(ctx, inp, pose).shape[0]:
                self.done = True
                return Veto(VetoKind.STANDS)
            self.asked += 1
            return Veto(VetoKind.LOOK)
        self.done = True
        copies = explaining_copies(ctx, inp, pose)
        if not copies.shape[0]:
            return Veto(VetoKind.STANDS)
        poses = np.vstack([pose[None, :], copies])
        answer = ctx.keyframes.verify(poses, inp.image)
        ctx.record.last_camera_check = (poses, answer)
        if answer.index is None or answer.index == 0:
            return Veto(VetoKind.STANDS)
        return Veto(
            VetoKind.VETOED,
            f"the camera verified a rotated copy of the operator's pose, not the pose "
            f"({answer.reason}): the operator's choice among the copies is not believed",
        )
