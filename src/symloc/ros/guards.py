"""Guards that keep the node's time base and odometry sane (used by :class:`NodeCore`).

A robot sends the odd bad stamp or pose: an Odometry stamped 20 s in the future, a clock that
jumps (a simulator restart, a looping bag), odometry that leaps by 1e154 m. Adopting such a value
would make every later good message look "backwards" or throw AMCL off for good. The policy, the
same for time and for odometry poses:

* a value close to the current reference is accepted and becomes the reference;
* a value far from it is **dropped, not adopted**;
* but when :data:`CONFIRM` far values in a row agree with each other (and, for time, come from
  every sensor stream that has been feeding the node), the world really changed (a clock jump,
  an odometry reset): they become the new reference and the caller resets what depended on the
  old one.

So a single outlier costs one message, a real jump costs :data:`CONFIRM` messages, and no
value, however absurd, can leave the node stuck: whatever arrives consistently wins within
:data:`CONFIRM` messages.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import compose, inverse

__all__ = [
    "CLOCK_MEMORY",
    "CONFIRM",
    "MAX_ODOM_COORDINATE",
    "BeamCountGate",
    "OdometryGate",
    "StampGate",
    "Verdict",
]

#: Far values in a row, agreeing with each other, that make a new reference.
CONFIRM = 3
#: Accepted stamps whose median is the node's clock.
CLOCK_MEMORY = 9
#: Odometry coordinates beyond this [m] are corrupt (float64 keeps sub-millimetre steps below it).
MAX_ODOM_COORDINATE = 1e9

#: ``ok``: accept; ``far``: drop (not adopted); ``rebase``: accept as a new reference.
Verdict = Literal["ok", "far", "rebase"]

FloatArray = NDArray[np.float64]


@dataclass
class StampGate:
    """One time base for the sensor streams (scan, odometry, image).

    Parameters
    ----------
    max_jump : float
        Largest distance [s] of a stamp from the node's clock that is taken as the same time
        base. The clock is the median of the last :data:`CLOCK_MEMORY` accepted stamps, so one
        odd stamp that is still within ``max_jump`` does not move it.
    required : iterable of str
        Streams that must all be among the confirming stamps of a new time base once they have
        fed the node (a clock jump moves every stream; one broken publisher must not drag the
        others along). Other streams (images) count but are not required.

    A caller that knows when each message was received on a clock of its own (a bag's log
    time, ``received`` in :meth:`check`) lets the gate tell a pause from a jump: a stamp far
    from the node's clock whose lag behind the receiving clock (``stamp - received``) is the
    usual one is time that passed (a robot that stood still and sent nothing, a recording
    paused, a log that keeps only the scans where the robot moved), not a jump, and is
    accepted. Stamps on another clock than the receiver's (a constant lag, however large) are
    the same time base too. A jump is a stamp that moved and whose lag moved with it.
    """

    max_jump: float
    required: Iterable[str] = ("scan", "odom")
    _recent: deque[float] = field(default_factory=lambda: deque(maxlen=CLOCK_MEMORY))
    _lags: deque[float] = field(default_factory=lambda: deque(maxlen=CLOCK_MEMORY))
    _active: set[str] = field(default_factory=set)
    _pending: list[tuple[float, str, float | None]] = field(default_factory=list)
    #: stamps accepted only because their lag was the usual one (pauses in the stream)
    pauses: int = 0

    @property
    def clock(self) -> float | None:
        """The node's clock [s]: the median of the recent accepted stamps (None before any)."""
        return float(np.median(self._recent)) if self._recent else None

    @property
    def lag(self) -> float | None:
        """The usual ``stamp - received`` [s] of the recent accepted stamps (None: unknown)."""
        return float(np.median(self._lags)) if self._lags else None

    def check(self, stamp: float, stream: str, received: float | None = None) -> Verdict:
        """Judge ``stamp`` [s] of a message of ``stream``, received at ``received`` [s] on the
        receiver's clock (None: unknown); ``rebase`` moves the clock to it."""
        clock = self.clock
        lag = None if received is None else stamp - received
        usual = self.lag
        near = clock is None or abs(stamp - clock) <= self.max_jump
        in_step = lag is not None and usual is not None and abs(lag - usual) <= self.max_jump
        if near or in_step:
            if not near:
                self.pauses += 1
                self._recent.clear()  # the clock moves on with the time that passed
            self._recent.append(stamp)
            if lag is not None:
                self._lags.append(lag)
            self._pending.clear()
            if stream in self.required:
                self._active.add(stream)
            return "ok"
        keep = [(s, n, g) for s, n, g in self._pending if abs(s - stamp) <= self.max_jump]
        self._pending = [*keep, (stamp, stream, lag)]
        streams = {n for _, n, _ in self._pending}
        if len(self._pending) >= CONFIRM and self._active <= streams:
            self._recent.clear()
            self._recent.extend(s for s, _, _ in self._pending)
            self._lags.clear()
            self._lags.extend(g for _, _, g in self._pending if g is not None)
            self._active = streams & set(self.required)
            self._pending.clear()
            return "rebase"
        return "far"


@dataclass
class OdometryGate:
    """Odometry poses that leap faster than a robot can move are dropped, unless they persist.

    Accepted readings are mapped through a correction ``fix`` (odom_corrected <- odom_raw),
    identity until the odometry is reset: then the first reading of the new base is taken to be
    where the robot was (no motion across the reset), so the localizer sees continuous odometry.

    Parameters
    ----------
    max_speed : float
        Fastest plausible motion [m/s]; a step is allowed ``max_speed * max(dt, 0.1 s)``.
    """

    max_speed: float
    fix: FloatArray = field(default_factory=lambda: np.zeros(3))
    _last: tuple[float | None, FloatArray] | None = None  # (stamp, raw pose) last accepted
    _pending: list[tuple[float | None, FloatArray]] = field(default_factory=list)

    @staticmethod
    def absurd(pose: FloatArray) -> bool:
        """Non-finite, or a coordinate beyond :data:`MAX_ODOM_COORDINATE`."""
        return bool(not np.all(np.isfinite(pose)) or np.any(np.abs(pose[:2]) > MAX_ODOM_COORDINATE))

    def _close(
        self, a: tuple[float | None, FloatArray], b: tuple[float | None, FloatArray]
    ) -> bool:
        dt = 0.0 if a[0] is None or b[0] is None else abs(b[0] - a[0])
        step = math.hypot(float(b[1][0] - a[1][0]), float(b[1][1] - a[1][1]))
        return step <= self.max_speed * max(dt, 0.1)

    def check(self, stamp: float, raw: FloatArray) -> Verdict:
        """Judge the raw odometry pose ``(3,)`` at ``stamp``; ``rebase`` re-anchors ``fix``."""
        now: tuple[float | None, FloatArray] = (float(stamp), np.asarray(raw, dtype=np.float64))
        if self._last is None or self._close(self._last, now):
            self._last = now
            self._pending.clear()
            return "ok"
        keep = [p for p in self._pending if self._close(p, now)]
        self._pending = [*keep, now]
        if len(self._pending) < CONFIRM:
            return "far"
        # the robot is taken to be where the last accepted reading put it
        first = self._pending[0][1]
        self.fix = compose(self.correct(self._last[1]), inverse(first))
        self._last = now
        self._pending.clear()
        return "rebase"

    def correct(self, raw: FloatArray) -> FloatArray:
        """The corrected pose ``(3,)`` of a raw odometry pose."""
        return compose(self.fix, raw)

    def uncorrect(self, pose: FloatArray) -> FloatArray:
        """Back from the corrected to the raw odometry frame (for goals the robot follows)."""
        return compose(inverse(self.fix), pose)

    def restart_clock(self) -> None:
        """After a time-base change: keep the pose reference, forget its stamp (dt unknown)."""
        if self._last is not None:
            self._last = (None, self._last[1])
        self._pending.clear()


@dataclass
class BeamCountGate:
    """The beam count of the scans: set by the first scan used, replaced when it changes.

    A scan of another length than the scans used is dropped (a truncated or foreign scan), but
    when :data:`CONFIRM` scans in a row have the same new length (no scan of the old length in
    between), the laser really changed (a driver restarted with another resolution, or the
    first scan was the odd one): the new length becomes the beam count. The localizer reads
    each scan's own geometry, so nothing else has to change.
    """

    count: int | None = None
    _candidate: int | None = None
    _seen: int = 0

    def check(self, n: int) -> Verdict:
        """Judge a scan of ``n`` beams; ``rebase``: ``n`` is the beam count from now on."""
        if self.count is None or n == self.count:
            self._candidate, self._seen = None, 0
            return "ok"
        if n != self._candidate:
            self._candidate, self._seen = n, 0
        self._seen += 1
        if self._seen < CONFIRM:
            return "far"
        self.count, self._candidate, self._seen = n, None, 0
        return "rebase"

    def used(self, n: int) -> None:
        """A scan of ``n`` beams was used: the first one sets the beam count."""
        if self.count is None:
            self.count = n

    @property
    def pending(self) -> int:
        """Scans in a row of the new length seen so far (0: none)."""
        return self._seen
