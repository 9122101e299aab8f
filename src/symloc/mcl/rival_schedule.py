"""One rival search spread over several scans, with a bounded cost per scan.

The rival search (:mod:`symloc.mcl.rival_search`) scans every free cell of the map: its cost
grows with the map's free area (a tenth of a second on a building, seconds on a campus). A
:class:`RivalSearchRun` holds one search, started with the evidence and the estimate of one
filter update, and advances it by at most a budget of pose-point pairs per call
(:meth:`RivalSearchRun.advance`), so the cost per scan is bounded whatever the map's size: a
small map's search still ends in the call that starts it, a large map's takes a few scans.

The report is the one :func:`~symloc.mcl.rival_search.find_rival` would return on the same
evidence (the slices score the same poses in the same order). It is about the place the
filter held when the run started; :class:`~symloc.mcl.confidence.ConfidenceJudge` applies it
only if the filter has followed that place since (the same ``track``, see
:mod:`symloc.mcl.confidence`), and drops the run otherwise.
"""

from __future__ import annotations

from collections.abc import Generator

from symloc.errors import ConfigurationError
from symloc.mcl.rival_search import RivalReport

__all__ = ["RivalSearchRun"]


class RivalSearchRun:
    """A rival search under way.

    Parameters
    ----------
    steps : generator
        :func:`~symloc.mcl.rival_search.rival_search_steps` (yields the pose-point pairs of
        each slice, returns the report).
    track : int
        The filter's track (``Confidence.track``) the search's evidence was gathered on.

    Attributes
    ----------
    track : int
    pairs : int
        Pose-point pairs scored so far.
    calls : int
        Calls of :meth:`advance` so far (the scans the search has taken).
    report : RivalReport or None
        The result once the search has ended.
    """

    def __init__(self, steps: Generator[int, None, RivalReport], *, track: int) -> None:
        self._steps = steps
        self.track = track
        self.pairs = 0
        self.calls = 0
        self.report: RivalReport | None = None

    def advance(self, budget: int) -> RivalReport | None:
        """Score slices until at least ``budget`` pose-point pairs (>= 1) were scored in this
        call or the search ended; the report once it has, else None.

        A slice is not cut: a call may exceed the budget by one slice (the search's
        ``chunk_pairs``, which the caller sets at most the budget).
        """
        if budget < 1:
            raise ConfigurationError(f"budget: expected an integer >= 1, got {budget!r}")
        if self.report is not None:
            return self.report
        self.calls += 1
        spent = 0
        while spent < budget:
            try:
                n = next(self._steps)
            except StopIteration as done:
                self.report = done.value
                return self.report
            spent += n
            self.pairs += n
        return None
