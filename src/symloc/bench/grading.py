"""Whole-trial grading: every pose published as tracking, at every scan, against the truth.

The tolerance is declared once (:data:`TOLERANCE`: 0.1 m and 5 degrees). A trial is

- **confident wrong** if *any* pose published as tracking, at *any* scan, lies outside the
  tolerance (not only the last one);
- **correct** if it published at least one pose as tracking since the trial's start (for a
  kidnapping: since the robot was carried away) and every pose it ever published lay inside;
- **undetermined** if it published no pose as tracking since then (and none wrong before).

Each trial also reports the time and distance from its start (or from the kidnapping) to the
first claim, the fraction of scans tracked, the error while tracking (mean and 95th
percentile, position and heading) and whether the published covariance covered the error:
the normalised estimation error squared ``NEES = e^T P^-1 e`` of each claim and the share of
claims whose error lies inside the published 95 % ellipsoid (NEES below the chi-square 95 %
quantile with 3 degrees of freedom, 7.81; Bar-Shalom, Li and Kirubarajan 2001, sec. 5.4).

**Heading** (corridors: the localizer's status ``axis``, heading known and position along the
corridor's axis not, :class:`~symloc.localizer.types.AxisPose`). An axis estimate is not a
claim and never makes a trial confident wrong; it is graded on its own:

- every scan's heading output is the axis estimate's heading, or the heading of a pose
  published as tracking;
- the trial's **heading is wrong** if any heading output, at any scan, is off by more than the
  tolerance's heading (5 degrees), as a confident wrong claim would be;
- its **first heading** is the first heading output since the start (or the kidnapping): right
  when within the tolerance;
- each axis estimate's position is honest when the truth lies inside its 95 % ellipsoid (NEES
  below 7.81, as for claims): the time of the first one, whether its heading was right and it
  covered the truth, and the share of axis estimates that covered it are reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import angle_diff

__all__ = [
    "CHI2_3DOF_95",
    "GRADES",
    "TOLERANCE",
    "ScanLog",
    "Tolerance",
    "TrialGrade",
    "coverage_at_scale",
    "grade_trial",
    "nees",
]

FloatArray = NDArray[np.float64]

GRADES = ("correct", "confident_wrong", "undetermined")
"""The three outcomes of a trial."""

CHI2_3DOF_95 = 7.814727903251178
"""95 % quantile of the chi-square distribution with 3 degrees of freedom."""


@dataclass(frozen=True)
class Tolerance:
    """When a claimed pose counts as right: within ``position`` [m] and ``heading`` [rad]."""

    position: float = 0.1
    heading: float = math.radians(5.0)

    def describe(self) -> str:
        """``"0.1 m and 5 deg"``."""
        return f"{self.position:g} m and {math.degrees(self.heading):g} deg"


TOLERANCE = Tolerance()
"""The one tolerance of the bench: 0.1 m and 5 degrees."""


@dataclass
class ScanLog:
    """What happened at each scan of a trial (appended by the trial runner).

    ``t`` [s], ``truth`` (3,) true pose, ``status`` the published status, ``pose`` (3,) the
    pose published as tracking (None otherwise), ``cov`` (3, 3) its covariance, ``distance``
    [m] travelled since the trial started, ``reason`` one line of why; ``axis`` (3,) and
    ``axis_cov`` (3, 3) the axis estimate (status ``axis``: the middle of the segment with the
    decided heading, and its elongated covariance; None otherwise).
    """

    t: list[float] = field(default_factory=list)
    truth: list[FloatArray] = field(default_factory=list)
    status: list[str] = field(default_factory=list)
    pose: list[FloatArray | None] = field(default_factory=list)
    cov: list[FloatArray | None] = field(default_factory=list)
    distance: list[float] = field(default_factory=list)
    reason: list[str] = field(default_factory=list)
    axis: list[FloatArray | None] = field(default_factory=list)
    axis_cov: list[FloatArray | None] = field(default_factory=list)

    def append(
        self,
        t: float,
        truth: FloatArray,
        status: str,
        pose: FloatArray | None,
        cov: FloatArray | None,
        distance: float,
        reason: str = "",
        axis: tuple[FloatArray, FloatArray] | None = None,
    ) -> None:
        """Record one scan (``axis``: the axis estimate's pose (3,) and covariance (3, 3))."""
        self.t.append(float(t))
        self.truth.append(np.asarray(truth, dtype=np.float64).copy())
        self.status.append(status)
        self.pose.append(None if pose is None else np.asarray(pose, dtype=np.float64).copy())
        self.cov.append(None if cov is None else np.asarray(cov, dtype=np.float64).copy())
        self.distance.append(float(distance))
        self.reason.append(reason)
        self.axis.append(None if axis is None else np.asarray(axis[0], dtype=np.float64).copy())
        self.axis_cov.append(None if axis is None else np.asarray(axis[1], dtype=np.float64).copy())

    def __len__(self) -> int:
        return len(self.t)


@dataclass(frozen=True)
class TrialGrade:
    """The grade of one trial (see the module docstring); times in s, distances in m,
    angles in rad; NaN where undefined (e.g. no claim).

    The heading's grade (status ``axis``): ``axis_estimates`` scans with an axis estimate;
    ``time_to_axis`` from the start (or the kidnapping) to the first since then;
    ``first_axis_heading_error`` its heading error, ``first_axis_heading_ok`` whether within
    the tolerance and ``first_axis_covered`` whether the truth lay inside its 95 % ellipsoid
    (None without one); ``axis_coverage`` the share of axis estimates that covered the truth;
    ``axis_heading_wrong`` axis estimates whose heading was off; ``time_to_heading`` to the
    first heading output (axis or tracking) since the start, ``first_heading_ok`` whether it
    was right (None without one); ``heading_wrong`` whether any heading output, at any scan,
    was off by more than the tolerance.

    ``nees_values``: each claim's NEES in scan order, to four significant digits (None where
    the covariance is singular), so that a calibration of the published covariance
    (:func:`coverage_at_scale`) can pool the claims of many trials."""

    grade: str
    claims: int
    scans: int
    time_to_claim: float
    distance_to_claim: float
    fraction_tracking: float
    error_mean: float
    error_p95: float
    heading_error_mean: float
    heading_error_p95: float
    nees_mean: float
    coverage: float
    worst_position_error: float
    worst_heading_error: float
    first_wrong_t: float
    first_wrong_reason: str
    axis_estimates: int = 0
    time_to_axis: float = math.nan
    first_axis_heading_error: float = math.nan
    first_axis_heading_ok: bool | None = None
    first_axis_covered: bool | None = None
    axis_coverage: float = math.nan
    axis_heading_wrong: int = 0
    time_to_heading: float = math.nan
    first_heading_ok: bool | None = None
    heading_wrong: bool = False
    nees_values: tuple[float | None, ...] = ()

    def as_dict(self) -> dict[str, float | int | str | bool | None]:
        """Plain values for JSON."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def nees(error: FloatArray, covariance: FloatArray) -> float:
    """``e^T P^-1 e`` for a pose error ``(3,)`` (heading wrapped) and covariance ``(3, 3)``.

    ``inf`` when ``P`` is singular or not positive definite (a claim with no uncertainty
    cannot cover any error).
    """
    e = np.asarray(error, dtype=np.float64).copy()
    e[2] = float(angle_diff(e[2], 0.0))
    try:
        c = np.linalg.cholesky(np.asarray(covariance, dtype=np.float64))
    except np.linalg.LinAlgError:
        return math.inf
    z = np.linalg.solve(c, e)
    return float(z @ z)


def grade_trial(
    log: ScanLog,
    *,
    tolerance: Tolerance = TOLERANCE,
    start: int = 0,
) -> TrialGrade:
    """Grade the scans ``log[start:]`` (``start``: the kidnapping's scan for time-to-claim;
    claims before it are graded too, since they were published)."""
    n = len(log)
    claimed = [i for i in range(n) if log.pose[i] is not None]
    pos_err = np.full(n, np.nan)
    head_err = np.full(n, np.nan)
    for i in claimed:
        p = log.pose[i]
        assert p is not None
        pos_err[i] = float(np.hypot(*(p[:2] - log.truth[i][:2])))
        head_err[i] = abs(float(angle_diff(p[2], log.truth[i][2])))
    wrong = [
        i for i in claimed if pos_err[i] > tolerance.position or head_err[i] > tolerance.heading
    ]
    after = [i for i in claimed if i >= start]
    verdict = "confident_wrong" if wrong else ("correct" if after else "undetermined")
    t0 = log.t[start] if n > start else math.nan
    d0 = log.distance[start] if n > start else math.nan
    first = after[0] if after else None
    nees_vals = []
    for i in claimed:
        c = log.cov[i]
        p = log.pose[i]
        if c is None or p is None:
            continue
        nees_vals.append(nees(p - log.truth[i], c))
    finite_nees = [v for v in nees_vals if math.isfinite(v)]
    ce = pos_err[claimed] if claimed else np.zeros(0)
    he = head_err[claimed] if claimed else np.zeros(0)
    worst = int(np.argmax(ce)) if claimed else -1
    grade = TrialGrade(
        grade=verdict,
        claims=len(claimed),
        scans=n,
        time_to_claim=(log.t[first] - t0) if first is not None else math.nan,
        distance_to_claim=(log.distance[first] - d0) if first is not None else math.nan,
        fraction_tracking=len(claimed) / n if n else math.nan,
        error_mean=float(np.mean(ce)) if claimed else math.nan,
        error_p95=float(np.percentile(ce, 95)) if claimed else math.nan,
        heading_error_mean=float(np.mean(he)) if claimed else math.nan,
        heading_error_p95=float(np.percentile(he, 95)) if claimed else math.nan,
        nees_mean=float(np.mean(finite_nees)) if finite_nees else math.nan,
        coverage=float(np.mean([v <= CHI2_3DOF_95 for v in nees_vals])) if nees_vals else math.nan,
        worst_position_error=float(ce[worst]) if claimed else math.nan,
        worst_heading_error=float(np.max(he)) if claimed else math.nan,
        first_wrong_t=log.t[wrong[0]] if wrong else math.nan,
        first_wrong_reason=log.reason[wrong[0]] if wrong else "",
        nees_values=tuple(float(f"{v:.4g}") if math.isfinite(v) else None for v in nees_vals),
    )
    return replace(grade, **_heading_grade(log, tolerance, start, head_err))


def _heading_grade(
    log: ScanLog, tolerance: Tolerance, start: int, claim_heading_error: FloatArray
) -> dict[str, Any]:
    """The heading's fields of :class:`TrialGrade` (see the module docstring);
    ``claim_heading_error`` (N,) [rad] of each scan's tracking claim (NaN: no claim)."""
    n = len(log)
    axis_err = np.full(n, np.nan)
    covered = np.zeros(n, dtype=bool)
    rows = [i for i in range(n) if log.axis[i] is not None]
    for i in rows:
        p, c = log.axis[i], log.axis_cov[i]
        assert p is not None
        assert c is not None
        axis_err[i] = abs(float(angle_diff(p[2], log.truth[i][2])))
        covered[i] = nees(p - log.truth[i], c) <= CHI2_3DOF_95
    heading_err = np.where(np.isnan(axis_err), claim_heading_error, axis_err)
    outputs = [i for i in range(start, n) if math.isfinite(heading_err[i])]
    first_axis = next((i for i in rows if i >= start), None)
    first = outputs[0] if outputs else None
    t0 = log.t[start] if n > start else math.nan
    tol = tolerance.heading
    return {
        "axis_estimates": len(rows),
        "time_to_axis": log.t[first_axis] - t0 if first_axis is not None else math.nan,
        "first_axis_heading_error": (
            float(axis_err[first_axis]) if first_axis is not None else math.nan
        ),
        "first_axis_heading_ok": (
            bool(axis_err[first_axis] <= tol) if first_axis is not None else None
        ),
        "first_axis_covered": bool(covered[first_axis]) if first_axis is not None else None,
        "axis_coverage": float(np.mean(covered[rows])) if rows else math.nan,
        "axis_heading_wrong": int(np.count_nonzero(axis_err > tol)),
        "time_to_heading": log.t[first] - t0 if first is not None else math.nan,
        "first_heading_ok": bool(heading_err[first] <= tol) if first is not None else None,
        "heading_wrong": bool(np.any(np.nan_to_num(heading_err, nan=0.0) > tol)),
    }


def coverage_at_scale(nees_values: list[float | None], scale: float) -> float:
    """The share of claims whose error lies inside the 95 % ellipsoid of their published
    covariance multiplied by ``scale`` (a variance factor): ``NEES / scale <= 7.81``.

    ``nees_values`` are :attr:`TrialGrade.nees_values` pooled over trials (None: a singular
    covariance, never covering). NaN for no claims.
    """
    if not scale > 0.0:
        raise ValueError(f"coverage_at_scale: expected a scale > 0, got {scale!r}")
    if not nees_values:
        return math.nan
    v = np.array([math.inf if x is None else x for x in nees_values], dtype=np.float64)
    return float(np.mean(v <= CHI2_3DOF_95 * scale))
