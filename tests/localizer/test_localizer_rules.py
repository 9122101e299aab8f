"""The localizer's small parts: the Streak rule, the bounded notes, the typed verdicts."""

from __future__ import annotations

import logging

import pytest

from symloc.errors import ConfigurationError
from symloc.localizer import Decision, DecisionStatus
from symloc.localizer.notes import Notes
from symloc.localizer.rules import Streak


def test_streak_counts_to_n_and_starts_over() -> None:
    s = Streak(3)
    assert [s.hit(), s.hit()] == [False, False]
    s.miss()
    assert s.count == 0
    assert [s.hit(), s.hit(), s.hit(), s.hit()] == [False, False, True, True]
    assert s.reached
    s.reset()
    assert not s.reached
    with pytest.raises(ConfigurationError, match=r"Streak\.n"):
        Streak(0)


def test_notes_keep_the_last_ones_log_them_and_say_a_lasting_state_once(
    caplog: pytest.LogCaptureFixture,
) -> None:
    notes = Notes(logging.getLogger("symloc.test"), maxlen=3)
    with caplog.at_level(logging.INFO, logger="symloc.test"):
        for text in ("a", "b", "c", "d"):
            notes(text)
        notes.note_once("d")
        notes.note_once("e")
    assert list(notes) == ["c", "d", "e"]
    assert notes[-1] == "e"
    assert notes[-2:] == ["d", "e"]
    assert len(notes) == 3
    assert [r.getMessage() for r in caplog.records] == ["a", "b", "c", "d", "e"]


def test_decision_status_is_an_enum_that_keeps_its_value() -> None:
    d = Decision("no_match", reason="low")
    assert d.status is DecisionStatus.NO_MATCH
    assert d.status.value == "no_match"
    assert Decision(DecisionStatus.DECIDED, 1).status is DecisionStatus.DECIDED
    with pytest.raises(ConfigurationError, match=r"Decision\.status"):
        Decision("maybe")
