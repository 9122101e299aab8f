"""Whole-trial grading: any wrong claim at any scan makes the trial confident wrong."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.bench.grading import CHI2_3DOF_95, TOLERANCE, ScanLog, grade_trial, nees
from symloc.bench.stats import json_safe, wilson_interval

COV = np.diag([0.05**2, 0.05**2, math.radians(2.0) ** 2])


def _log(errors: list[tuple[float, float] | None], dt: float = 0.1) -> ScanLog:
    """A straight drive along x at 1 m/s; ``errors[i]`` = (dx [m], dtheta [deg]) of the claim
    at scan i, or None for no claim."""
    log = ScanLog()
    for i, e in enumerate(errors):
        truth = np.array([i * dt, 0.0, 0.0])
        pose = None if e is None else truth + np.array([e[0], 0.0, math.radians(e[1])])
        log.append(i * dt, truth, "tracking" if e else "lost", pose, COV if e else None, i * dt)
    return log


def test_one_wrong_claim_anywhere_makes_the_trial_confident_wrong() -> None:
    good = [None, None, (0.01, 0.5), (0.02, 1.0), (0.0, 0.0)]
    assert grade_trial(_log(good)).grade == "correct"
    for i in (2, 3, 4):
        bad = list(good)
        bad[i] = (0.0, 6.0)  # heading 6 deg off, position exact
        g = grade_trial(_log(bad))
        assert g.grade == "confident_wrong"
        assert g.first_wrong_t == pytest.approx(0.1 * i)
    far = list(good)
    far[3] = (0.11, 0.0)
    assert grade_trial(_log(far)).grade == "confident_wrong"


def test_no_claim_is_undetermined_and_timing_is_from_the_start() -> None:
    g = grade_trial(_log([None] * 5))
    assert g.grade == "undetermined"
    assert math.isnan(g.time_to_claim)
    g = grade_trial(_log([None, None, None, (0.0, 0.0), (0.0, 0.0)]))
    assert g.time_to_claim == pytest.approx(0.3)
    assert g.distance_to_claim == pytest.approx(0.3)
    assert g.fraction_tracking == pytest.approx(0.4)


def test_kidnap_trial_needs_a_claim_after_the_kidnapping() -> None:
    # tracked before the kidnapping (scan 2), then never claimed again: undetermined
    log = _log([(0.0, 0.0), (0.0, 0.0), None, None, None])
    assert grade_trial(log, start=2).grade == "undetermined"
    # a claim after it, all right: correct, time counted from the kidnapping
    log = _log([(0.0, 0.0), (0.0, 0.0), None, (0.01, 1.0), (0.0, 0.0)])
    g = grade_trial(log, start=2)
    assert g.grade == "correct"
    assert g.time_to_claim == pytest.approx(0.1)
    # a wrong claim before the kidnapping still counts
    log = _log([(0.0, 9.0), (0.0, 0.0), None, (0.01, 1.0), (0.0, 0.0)])
    assert grade_trial(log, start=2).grade == "confident_wrong"


def test_nees_and_coverage() -> None:
    e = np.array([0.05, 0.0, 0.0])
    assert nees(e, COV) == pytest.approx(1.0)
    assert nees(np.array([0.0, 0.0, 2 * math.pi]), COV) == pytest.approx(0.0, abs=1e-9)
    assert math.isinf(nees(e, np.zeros((3, 3))))
    # 2.5 sigma in x alone: NEES 6.25 < 7.81, inside; 3 sigma: 9 > 7.81, outside
    g = grade_trial(_log([(0.125, 0.0), (0.15, 0.0)]))
    assert g.coverage == pytest.approx(0.5)
    assert g.grade == "confident_wrong"  # 0.125 m and 0.15 m exceed 0.1 m
    assert pytest.approx(7.8147, abs=1e-4) == CHI2_3DOF_95


def test_wilson_interval_known_values() -> None:
    lo, hi = wilson_interval(0, 3000)
    assert lo == 0.0
    assert hi == pytest.approx(1.2787e-3, rel=1e-3)  # the "0 in 3,000" upper bound
    lo, hi = wilson_interval(5, 10)
    assert lo == pytest.approx(0.2366, abs=1e-4)
    assert hi == pytest.approx(0.7634, abs=1e-4)
    assert wilson_interval(0, 0) == (0.0, 1.0)
    with pytest.raises(ValueError, match="successes"):
        wilson_interval(4, 3)


def test_json_safe_replaces_non_finite_floats() -> None:
    doc = {"a": math.nan, "b": [1.0, math.inf, {"c": -math.inf}], "d": "x", 3: 2}
    assert json_safe(doc) == {"a": None, "b": [1.0, None, {"c": None}], "d": "x", "3": 2}


def test_tolerance_is_declared_once() -> None:
    assert TOLERANCE.position == 0.1
    assert math.degrees(TOLERANCE.heading) == pytest.approx(5.0)
    assert TOLERANCE.describe() == "0.1 m and 5 deg"
