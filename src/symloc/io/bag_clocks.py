"""Which clock each stream of a bag is stamped with, told from the bag's log times.

A bag stores two times per message: the header stamp (the sender's clock) and the log time
(the recorder's clock, when it received the message). On one robot both clocks are usually the
same clock and a message's lag ``stamp - log_time`` is a small negative number (its transport
latency, a scan's sweep time). But a driver may stamp with a clock of its own: a laser
stamping with its device clock from boot, a camera with a clock that started in 1970, a robot
whose odometry comes from another computer that is not synchronised. Then the scans' stamps
and the odometry's are seconds or decades apart, and no scan finds the odometry at its stamp.

:func:`stream_lags` measures each stream's lag behind the recorder: the 90th percentile of
``stamp - log_time`` over its messages, i.e. the messages that arrived fastest (the minimum-delay
filter of clock synchronisation: a message held up in a burst only ever arrives later, so the
fastest ones show the clock offset best; the top tenth is left out against outliers).
:func:`clock_offsets` tells the streams whose lag differs from the odometry's by more than
``tolerance`` (more than a transport latency can explain: another clock) and the offset that
puts their stamps on the odometry's clock. The accuracy of such a re-stamping is about the
spread of the two streams' latencies, so it is reported, never silent.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from symloc.io.rosbag import BagMessage

__all__ = ["ClockOffsets", "clock_offsets", "stream_lags"]

#: Streams that are re-stamped onto the odometry's clock when theirs is another one.
_STREAMS = ("scan", "image")


def stream_lags(messages: Iterable[BagMessage]) -> dict[str, tuple[float, float, int]]:
    """Per kind (``scan``, ``odom``, ``image``): the lag ``stamp - log_time`` [s] of the
    fastest messages (90th percentile), the spread of the lags (90th minus 10th percentile)
    [s], and the message count."""
    lags: dict[str, list[float]] = defaultdict(list)
    for m in messages:
        if m.kind in ("scan", "odom", "image"):
            lags[m.kind].append(m.stamp - m.log_time * 1e-9)
    out: dict[str, tuple[float, float, int]] = {}
    for kind, values in lags.items():
        a = np.asarray(values, dtype=np.float64)
        hi, lo = np.percentile(a, [90.0, 10.0])
        out[kind] = (float(hi), float(hi - lo), int(a.size))
    return out


@dataclass(frozen=True)
class ClockOffsets:
    """Offsets [s] to add to each kind's stamps to put them on the odometry's clock (only the
    kinds on another clock appear), and one line per re-stamped stream for the user."""

    offsets: dict[str, float]
    notes: list[str]

    def shift(self, kind: str) -> float:
        """The offset [s] for ``kind`` (0 when it is on the odometry's clock)."""
        return self.offsets.get(kind, 0.0)


def clock_offsets(lags: dict[str, tuple[float, float, int]], tolerance: float) -> ClockOffsets:
    """The streams on another clock than the odometry's and their offsets.

    Parameters
    ----------
    lags : dict
        From :func:`stream_lags`.
    tolerance : float
        Largest difference [s] of two streams' usual lags that is taken as latency on one
        clock (the node's ``transform_tolerance``: a scan further than that from its odometry
        would be dropped anyway).
    """
    if "odom" not in lags:
        return ClockOffsets({}, [])
    ref = lags["odom"][0]
    offsets: dict[str, float] = {}
    notes: list[str] = []
    for kind in _STREAMS:
        if kind not in lags:
            continue
        lag, spread, n = lags[kind]
        if abs(lag - ref) <= tolerance:
            continue
        offsets[kind] = ref - lag
        accuracy = max(spread, lags["odom"][1], 1e-3)
        notes.append(
            f"{kind} stamps are {lag - ref:+.3f} s from the odometry's (stamp - log time of the"
            f" fastest of {n} messages): another clock; re-stamped onto the odometry's clock by"
            f" the recording's log times (accuracy about {accuracy:.3f} s, the spread of the"
            " recording latency)"
        )
    return ClockOffsets(offsets, notes)
