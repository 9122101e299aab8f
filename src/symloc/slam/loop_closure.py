"""Verifying loop-closure candidates before they reach the pose graph.

A candidate is a scan (graph node) matched against an older submap with a wide window: the
measured pose ``z`` of the node in the submap's frame, the match score, the runner-up score
outside a neighbourhood of the best pose, and the match's constraint (degeneracy). Each is
checked in turn, and the first failed test is its reason for rejection:

1. ``score``: the match explains the scan (score >= ``min_score``); candidates below are not
   counted as rejected closures, they are searches that found nothing;
2. ``ambiguous``: no other pose in the window scores almost as well (runner-up below
   ``score - ambiguity_margin``): a corridor or a repeated room gives several;
3. ``degenerate``: the match constrains every direction (:mod:`symloc.slam.degeneracy`);
4. consistency: the *correction* the closure asks for, ``nu`` = the loop-implied node pose
   in the frame of the node's current estimate, must be explained by drift. It is accepted
   at once when ``|nu|`` is within the gate ``gate_trans + drift_trans * d`` (and likewise in
   heading), ``d`` the trajectory length [m] since the last accepted closure, the drift rates
   learnt from the closures accepted so far (their ``|nu| / d``, 90th percentile, never below
   the defaults). A larger correction waits (``pending``) until another candidate from a
   nearby node asks for the same correction (within ``agree_trans``, ``agree_rot``): two
   independent matches agreeing on a large correction are a real loop; one alone may be a
   look-alike place. A pending candidate that no other confirms within ``pending_nodes``
   nodes is rejected (``inconsistent``).

The pose graph's robust loss and its residual check (:mod:`symloc.slam.pose_graph`) are the
last line behind these tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import relative, wrap_angle

__all__ = ["LoopCandidate", "LoopVerifier", "LoopVerifierParams"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class LoopVerifierParams:
    """Settings of :class:`LoopVerifier` (see the module docstring)."""

    min_score: float = 0.55
    ambiguity_margin: float = 0.05
    gate_trans: float = 0.3
    gate_rot: float = math.radians(3.0)
    drift_trans: float = 0.02
    drift_rot: float = math.radians(0.3)
    agree_trans: float = 0.25
    agree_rot: float = math.radians(2.0)
    pending_nodes: int = 40

    def __post_init__(self) -> None:
        if not 0.0 <= self.min_score <= 1.0:
            raise ConfigurationError(
                f"LoopVerifierParams.min_score: expected a value in [0, 1], got {self.min_score}"
            )
        for name in (
            "ambiguity_margin",
            "gate_trans",
            "gate_rot",
            "drift_trans",
            "drift_rot",
            "agree_trans",
            "agree_rot",
        ):
            check_positive(getattr(self, name), f"LoopVerifierParams.{name}", allow_zero=True)
        if int(self.pending_nodes) != self.pending_nodes or self.pending_nodes < 1:
            raise ConfigurationError(
                f"LoopVerifierParams.pending_nodes: expected an integer >= 1, got"
                f" {self.pending_nodes}"
            )


@dataclass(slots=True)
class LoopCandidate:
    """One loop-closure match of node ``node`` against submap ``submap``.

    ``measurement`` (3,): the node's pose in the submap frame; ``covariance`` (3, 3);
    ``correction`` (3,): the loop-implied node pose in the frame of its current estimate;
    ``travel``: trajectory length [m] at the node; ``since_loop``: length since the last
    accepted closure [m].
    """

    submap: int
    node: int
    measurement: FloatArray
    covariance: FloatArray
    score: float
    runner_up: float
    degenerate: bool
    correction: FloatArray
    travel: float
    since_loop: float
    reason: str = ""
    extra: dict[str, float] = field(default_factory=dict)


class LoopVerifier:
    """Sorts candidates into accepted and rejected (with reasons), keeping some pending."""

    def __init__(self, params: LoopVerifierParams | None = None) -> None:
        self.params = params if params is not None else LoopVerifierParams()
        self.pending: list[LoopCandidate] = []
        self.rejected: list[LoopCandidate] = []
        self._rates_t: list[float] = []
        self._rates_r: list[float] = []

    def drift_rates(self) -> tuple[float, float]:
        """``(m per m, rad per m)``: learnt from accepted corrections, at least the defaults."""
        p = self.params
        rt = float(np.percentile(self._rates_t, 90)) if len(self._rates_t) >= 5 else 0.0
        rr = float(np.percentile(self._rates_r, 90)) if len(self._rates_r) >= 5 else 0.0
        return max(p.drift_trans, rt), max(p.drift_rot, rr)

    def gate(self, since_loop: float) -> tuple[float, float]:
        """Largest correction [m], [rad] accepted without confirmation after ``since_loop`` m."""
        dt, dr = self.drift_rates()
        return self.params.gate_trans + dt * since_loop, self.params.gate_rot + dr * since_loop

    def _learn(self, c: LoopCandidate) -> None:
        d = max(c.since_loop, 5.0)
        self._rates_t.append(float(np.hypot(c.correction[0], c.correction[1])) / d)
        self._rates_r.append(abs(float(wrap_angle(c.correction[2]))) / d)

    def _agree(self, a: LoopCandidate, b: LoopCandidate) -> bool:
        p = self.params
        da = a.correction - b.correction
        return bool(
            math.hypot(float(da[0]), float(da[1])) <= p.agree_trans
            and abs(float(wrap_angle(da[2]))) <= p.agree_rot
        )

    def submit(
        self, c: LoopCandidate, node: int, *, min_score: float | None = None
    ) -> list[LoopCandidate]:
        """Check a candidate; returns the candidates accepted now (it and/or pending ones).

        ``min_score`` overrides ``params.min_score`` (the run's own score level).
        """
        p = self.params
        self._expire(node)
        if c.score < (p.min_score if min_score is None else min_score):
            return []
        if c.runner_up >= c.score - p.ambiguity_margin:
            c.reason = "ambiguous"
            self.rejected.append(c)
            return []
        if c.degenerate:
            c.reason = "degenerate"
            self.rejected.append(c)
            return []
        gt, gr = self.gate(c.since_loop)
        small = (
            math.hypot(float(c.correction[0]), float(c.correction[1])) <= gt
            and abs(float(wrap_angle(c.correction[2]))) <= gr
        )
        if small:
            self._learn(c)
            return [c]
        friends = [q for q in self.pending if self._agree(c, q)]
        if friends:
            for q in friends:
                self.pending.remove(q)
            accepted = [*friends, c]
            for q in accepted:
                self._learn(q)
            return accepted
        self.pending.append(c)
        return []

    def _expire(self, node: int) -> None:
        keep = []
        for q in self.pending:
            if node - q.node > self.params.pending_nodes:
                q.reason = "inconsistent"
                self.rejected.append(q)
            else:
                keep.append(q)
        self.pending = keep

    def finish(self) -> None:
        """End of the run: every still-pending candidate is rejected as unconfirmed."""
        for q in self.pending:
            q.reason = "inconsistent"
            self.rejected.append(q)
        self.pending = []

    def correction_of(self, estimate_in_submap: ArrayLike, measurement: ArrayLike) -> FloatArray:
        """``nu``: the measured node pose in the frame of its estimate (both in the submap)."""
        return np.asarray(relative(estimate_in_submap, measurement), dtype=np.float64)
