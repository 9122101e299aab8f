"""Whole-trial grading: any wrong claim at any scan makes the trial confident wrong."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.bench.grading import (
    CHI2_3DOF_95,
    TOLERANCE,
    ScanLog,
    coverage_at_scale,
    grade_trial,
    nees,
)
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


def test_each_claims_nees_is_kept_and_rescaled_coverage_pools_them() -> None:
    # claims 1, 2.5 and 3 sigma off in x (NEES 1, 6.25, 9), one scan without a claim
    g = grade_trial(_log([(0.05, 0.0), None, (0.125, 0.0), (0.15, 0.0)]))
    assert g.nees_values == pytest.approx((1.0, 6.25, 9.0))
    assert g.as_dict()["nees_values"] == g.nees_values
    assert coverage_at_scale(list(g.nees_values), 1.0) == pytest.approx(g.coverage)
    # half the variance doubles every NEES: only the first (2) stays inside 7.81
    assert coverage_at_scale(list(g.nees_values), 0.5) == pytest.approx(1 / 3)
    # twice the variance: 9 / 2 = 4.5 inside too
    assert coverage_at_scale(list(g.nees_values), 2.0) == pytest.approx(1.0)
    # a singular covariance never covers; no claims is NaN; a scale must be positive
    assert coverage_at_scale([None, 1.0], 1.0) == pytest.approx(0.5)
    assert math.isnan(coverage_at_scale([], 1.0))
    with pytest.raises(ValueError, match="scale > 0"):
        coverage_at_scale([1.0], 0.0)


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


AXIS_COV = np.diag([3.0**2, 0.05**2, math.radians(1.0) ** 2])


def _axis_log(rows: list[tuple[str, float, float] | None], start_claims: int = 99) -> ScanLog:
    """Scans along x at 1 m/s; ``rows[i]`` = (kind, along error [m], heading error [deg]) with
    kind ``"axis"`` (an axis estimate) or ``"claim"`` (a pose published as tracking)."""
    log = ScanLog()
    for i, r in enumerate(rows):
        truth = np.array([i * 0.1, 0.0, 0.0])
        if r is None:
            log.append(i * 0.1, truth, "lost", None, None, i * 0.1)
            continue
        kind, along, head = r
        pose = truth + np.array([along, 0.0, math.radians(head)])
        if kind == "axis":
            log.append(i * 0.1, truth, "axis", None, None, i * 0.1, axis=(pose, AXIS_COV))
        else:
            log.append(i * 0.1, truth, "tracking", pose, COV, i * 0.1)
    return log


def test_axis_estimates_are_graded_for_their_heading_never_as_claims() -> None:
    g = grade_trial(_axis_log([None, None, ("axis", 4.0, 1.0), ("axis", 12.0, 1.5), None]))
    assert g.grade == "undetermined"  # an axis estimate is no claim, however far along
    assert g.claims == 0
    assert g.axis_estimates == 2
    assert g.time_to_axis == pytest.approx(0.2)
    assert g.first_axis_heading_error == pytest.approx(math.radians(1.0))
    assert g.first_axis_heading_ok is True
    assert g.first_axis_covered is True  # 4 m along, std 3 m: inside
    assert g.axis_coverage == pytest.approx(0.5)  # 12 m along: outside
    assert g.first_heading_ok is True
    assert g.heading_wrong is False
    assert g.axis_heading_wrong == 0
    assert g.time_to_heading == pytest.approx(0.2)
    row = json_safe(g.as_dict())
    assert row["first_axis_covered"] is True
    assert "grade" in row  # the claim keys stay
    assert "coverage" in row


def test_a_wrong_axis_heading_at_any_scan_makes_the_heading_wrong() -> None:
    g = grade_trial(_axis_log([("axis", 0.0, 1.0), ("axis", 0.0, 7.0), ("axis", 0.0, 1.0)]))
    assert g.first_heading_ok is True
    assert g.heading_wrong is True
    assert g.axis_heading_wrong == 1
    assert g.grade == "undetermined"
    # a claim's heading counts as a heading output too: first output right, then a wrong claim
    g = grade_trial(_axis_log([("axis", 0.0, 1.0), ("claim", 0.0, 8.0)]))
    assert g.heading_wrong is True
    assert g.grade == "confident_wrong"
    # no axis estimate, no claim: no heading
    g = grade_trial(_axis_log([None, None]))
    assert g.first_heading_ok is None
    assert g.first_axis_covered is None
    assert g.heading_wrong is False
    assert math.isnan(g.time_to_axis)


def test_the_first_heading_is_counted_from_the_kidnapping() -> None:
    rows = [("claim", 0.0, 0.0), None, None, ("axis", 0.0, 179.0), ("axis", 0.0, 0.5)]
    g = grade_trial(_axis_log(rows), start=1)
    assert g.first_heading_ok is False  # the first heading since the kidnapping was flipped
    assert g.heading_wrong is True
    assert g.time_to_heading == pytest.approx(0.2)


def test_the_summary_counts_heading_correct_and_wrong() -> None:
    from symloc.bench.localization import summarize

    base = {"family": "corridor_long", "method": "decide", "claims": 0, "coverage": math.nan,
            "time_to_claim": math.nan, "distance_to_claim": math.nan, "error_p95": math.nan,
            "heading_error_p95": math.nan, "fraction_tracking": 0.0, "grade": "undetermined"}  # fmt: skip
    right = grade_trial(_axis_log([("axis", 0.0, 1.0)])).as_dict()
    wrong = grade_trial(_axis_log([("axis", 0.0, 1.0), ("axis", 0.0, 9.0)])).as_dict()
    old = dict(base)  # a row of an older JSON, without the heading's keys
    rows = [base | right, base | right, base | wrong, old]
    (fam, _all) = summarize(rows)
    assert fam["trials"] == 4
    assert fam["heading_correct"] == 3  # the first heading of the third was right too
    assert fam["heading_wrong"] == 1
    assert fam["axis_trials"] == 3
    assert fam["axis_first_covered_rate"] == pytest.approx(1.0)
    assert fam["median_time_to_heading_s"] == pytest.approx(0.0)
    assert fam["correct"] == 0
    assert fam["undetermined"] == 4
