"""When is AMCL's pose *confident*? The one definition every symloc experiment and the localizer use.

A pose estimate from :class:`~symloc.mcl.amcl.Amcl` is **confident** only when all of these
hold (each threshold is a field of :class:`ConfidenceConfig`):

1. **One dominant hypothesis**: the heaviest cluster holds at least ``min_weight_share``
   (default 0.9) of the particle weight. Two or more well-weighted clusters mean the filter
   itself does not know which place it is in (e.g. a symmetric room).
2. **That hypothesis is tight**: its *own* covariance (not the whole set's, which nav2
   publishes) has a position standard deviation (square root of the largest eigenvalue of the
   x-y block) at most ``max_xy_std`` (default 0.15 m) and a heading standard deviation at
   most ``max_theta_std`` (default 8 degrees). 0.15 m is half the 0.3 m tolerance with which
   the experiments call a pose correct, so the 2-sigma circle lies inside it; 8 degrees is the
   threshold the localizer used before this module existed. A heading error that large still
   moves a beam end point at 5 m by 0.7 m, which check 3 sees.
3. **The scan agrees with the map at the estimate**: the estimate lies in a free cell of the
   map (a robot cannot stand inside a wall or in space the map never observed), and placing
   the current scan at the estimated pose, at least ``min_scan_consistency`` (default 0.9) of
   its valid returning beams end within ``consistency_sigmas * sigma_hit`` (default 2 x 0.2 m
   = 0.4 m) of an occupied cell of the map's distance field (:func:`scan_consistency`). If
   the laser model's noise ``sigma_hit`` were right, about 95 % of the beams at the true pose
   would pass; the margin down to 90 % absorbs people, glass and map errors. Fewer than
   ``min_beams`` valid beams is not evidence: not confident.
4. **Sustained (hysteresis)**: checks 1-3 passed at each of the last ``hold_updates``
   (default 3) consecutive filter updates that integrated a scan, and between those updates
   the estimate moved as the odometry says (within ``max_jump_xy`` = 0.5 m and
   ``max_jump_theta`` = 20 degrees of the odometry-predicted pose), so a filter that hops
   from one hypothesis to another restarts the count. A call that did not integrate a scan
   (the robot moved less than ``update_min_d``) keeps the previous verdict; a failed check
   drops confidence at once.
5. **No rival place** (``rival_check``, default on): checks 1-4 can all pass on a wrong place
   that looks locally like the right one (a stretch of corridor, two identical offices): the
   particles at the right place died, so the filter cannot know. Once checks 1-4 hold, the
   scans of the current streak (up to ``evidence_updates`` = 10 updates, chained by the
   odometry into the robot's current frame) are matched against the *whole map*
   (:func:`symloc.mcl.rival_search.find_rival`: a correlative search over every free cell and
   heading with a provable upper bound, then refinement). If a pose farther than
   ``rival_min_distance`` = 1 m or ``rival_min_angle`` = 30 degrees from the estimate
   explains the evidence within ``rival_margin`` = 0.05 of the estimate's score (fraction of
   points within ``rival_tolerance_sigmas * sigma_hit`` = 0.2 m of an obstacle), the place is
   ambiguous: not confident, checked again after ``rival_recheck`` = 5 more updates with
   more evidence (then 10, 20, ...: a symmetric room stays ambiguous). Uniqueness must be
   proven: if the search's bound leaves more candidate places than it can check, the place
   counts as ambiguous. Once the place is unique, the verdict holds for as long as the filter
   follows it (its ``track``): it is searched again only when the estimate jumps to another
   place (farther than ``rival_min_distance`` or turned more than ``rival_min_angle`` from
   the odometry's prediction), the heaviest cluster loses its share (a new cluster), more
   than ``rival_grace`` = 5 updates in a row fail checks 1-3 (a doubt), or every
   ``rival_period`` = 1000 updates. A search scores at most ``rival_budget`` pose-point pairs
   per update (its cost grows with the map's free area; on a large map it takes a few
   updates, and the verdict waits for it): the cost per scan is bounded.

In a truly symmetric room a symmetric copy of the true pose matches the scans perfectly:
checks 1-4 pass on it (the other copies' particles die out), and only check 5 sees that the
place is ambiguous (the rival it reports *is* the symmetric copy).
``Confidence.locally_confident`` (checks 1-4 only; with ``rival_check=False`` it equals
``confident``) is what a nav2 user can get from the filter alone, and by it AMCL is confidently wrong in
symmetric rooms; telling the copies apart is the localizer's job (vision). A caller that has
resolved the ambiguity itself (the localizer after vision picked the copy) should track with
``locally_confident``; a caller that claims a pose from AMCL alone should use ``confident``.

The verdict is judged *after* the filter update, not inside it (beluga's ``amcl_core``
estimates after the update): :meth:`symloc.mcl.Amcl.update` only moves, weighs, resamples and
clusters the particles (bounded cost); a :class:`ConfidenceJudge` bound to the filter then
judges each of its results, keeps the hysteresis and the streak's evidence, and runs the rival
search when it is due, ``rival_budget`` pose-point pairs per update (a bounded cost per
scan, whatever the map's size). Call the judge on *every* result of
:meth:`~symloc.mcl.Amcl.update` (also those that integrated no scan: they keep the verdict),
or the hysteresis counts differently. For hand-fed results use :func:`assess` with
:func:`scan_consistency` (and :func:`~symloc.mcl.rival_search.find_rival`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Generator
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError
from symloc.geometry import compose, relative, transform_points, wrap_angle
from symloc.grid.distance_field import DistanceField
from symloc.mcl.beams import select_beams
from symloc.mcl.rival_schedule import RivalSearchRun
from symloc.mcl.rival_search import RivalReport, rival_search_steps
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan

if TYPE_CHECKING:
    from symloc.mcl.amcl import Amcl, AmclResult

__all__ = [
    "Confidence",
    "ConfidenceConfig",
    "ConfidenceJudge",
    "ScanConsistency",
    "assess",
    "hypothesis_std",
    "scan_consistency",
]

FloatArray = NDArray[np.float64]

_INT_FIELDS = (
    "min_beams",
    "hold_updates",
    "evidence_updates",
    "rival_recheck",
    "rival_max_points",
    "rival_grace",
    "rival_period",
    "rival_budget",
)


@dataclass(frozen=True)
class ConfidenceConfig:
    """Thresholds of the confidence definition (see the module docstring).

    Attributes
    ----------
    min_weight_share : float
        Weight fraction in (0.5, 1] the heaviest cluster must hold.
    max_xy_std : float
        Largest position standard deviation [m] (> 0) of that cluster.
    max_theta_std : float
        Largest heading standard deviation [rad] in (0, pi) of that cluster.
    consistency_sigmas : float
        A beam agrees with the map when its end point lies within this many ``sigma_hit``
        of an obstacle (> 0).
    min_scan_consistency : float
        Fraction in (0, 1] of valid beams that must agree.
    min_beams : int
        Fewest valid returning beams (>= 1) for the scan check to count.
    hold_updates : int
        Consecutive scan-integrating updates (>= 1) over which checks 1-3 must pass.
    max_jump_xy : float
        Largest disagreement [m] (> 0) between the estimate and the previous estimate moved
        by the odometry, before the hysteresis count restarts.
    max_jump_theta : float
        Same for the heading [rad], in (0, pi].
    rival_check : bool
        Run check 5 (global search for a rival place).
    rival_tolerance_sigmas : float
        Point-to-obstacle tolerance of the rival search in units of ``sigma_hit`` (> 0).
    rival_margin : float
        A rival scoring within this of the estimate makes the place ambiguous, in [0, 1).
    rival_min_distance : float
        A rival lies farther than this [m] (> 0) ...
    rival_min_angle : float
        ... or is turned more than this [rad], in (0, pi].
    evidence_updates : int
        Scans (>= 1) of the current streak used as evidence for the rival search.
    rival_recheck : int
        Updates (>= 1) to wait before searching again after the first ambiguous answer;
        doubled after each further one in the same streak.
    rival_max_points : int
        Evidence points (>= 10) the rival search uses (evenly sub-sampled).
    rival_grace : int
        Failed updates in a row (>= 0) during which a place proven unique is still followed:
        the estimate moves as the odometry says and the heaviest cluster keeps its share, but
        check 2 or 3 fails (a person in front of the laser, a wall a cell off the map). One
        more is a doubt, and the place must be proven again.
    rival_period : int
        Scan-integrating updates (>= 1) after which a place followed since it was proven
        unique is searched again anyway (the verdict stays confident meanwhile).
    rival_budget : int
        Pose-point pairs (>= 1) the rival search scores per filter update: a search of a
        large map is spread over several updates (bounded cost per scan), and the verdict
        waits for it.
    """

    min_weight_share: float = 0.9
    max_xy_std: float = 0.15
    max_theta_std: float = math.radians(8.0)
    consistency_sigmas: float = 2.0
    min_scan_consistency: float = 0.9
    min_beams: int = 10
    hold_updates: int = 3
    max_jump_xy: float = 0.5
    max_jump_theta: float = math.radians(20.0)
    rival_check: bool = True
    rival_tolerance_sigmas: float = 1.0
    rival_margin: float = 0.05
    rival_min_distance: float = 1.0
    rival_min_angle: float = math.radians(30.0)
    evidence_updates: int = 10
    rival_recheck: int = 5
    rival_max_points: int = 100
    rival_grace: int = 5
    rival_period: int = 1000
    rival_budget: int = 64_000_000

    def __post_init__(self) -> None:
        def need(ok: bool, name: str, what: str) -> None:
            if not ok:
                raise ConfigurationError(
                    f"ConfidenceConfig.{name}: expected {what}, got {getattr(self, name)!r}"
                )

        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "rival_check":
                need(isinstance(v, (bool, np.bool_)), f.name, "a bool")
            elif f.name in _INT_FIELDS:
                need(
                    isinstance(v, (int, np.integer)) and not isinstance(v, bool),
                    f.name,
                    "an integer",
                )
            else:
                need(
                    isinstance(v, (int, float, np.number))
                    and not isinstance(v, bool)
                    and math.isfinite(float(v)),
                    f.name,
                    "a finite number",
                )
        need(0.5 < self.min_weight_share <= 1.0, "min_weight_share", "a value in (0.5, 1]")
        need(self.max_xy_std > 0.0, "max_xy_std", "a value > 0 m")
        need(0.0 < self.max_theta_std < math.pi, "max_theta_std", "a value in (0, pi) rad")
        need(self.consistency_sigmas > 0.0, "consistency_sigmas", "a value > 0")
        need(
            0.0 < self.min_scan_consistency <= 1.0,
            "min_scan_consistency",
            "a value in (0, 1]",
        )
        need(self.min_beams >= 1, "min_beams", "an integer >= 1")
        need(self.hold_updates >= 1, "hold_updates", "an integer >= 1")
        need(self.max_jump_xy > 0.0, "max_jump_xy", "a value > 0 m")
        need(0.0 < self.max_jump_theta <= math.pi, "max_jump_theta", "a value in (0, pi] rad")
        need(self.rival_tolerance_sigmas > 0.0, "rival_tolerance_sigmas", "a value > 0")
        need(0.0 <= self.rival_margin < 1.0, "rival_margin", "a value in [0, 1)")
        need(self.rival_min_distance > 0.0, "rival_min_distance", "a value > 0 m")
        need(0.0 < self.rival_min_angle <= math.pi, "rival_min_angle", "a value in (0, pi] rad")
        need(self.evidence_updates >= 1, "evidence_updates", "an integer >= 1")
        need(self.rival_recheck >= 1, "rival_recheck", "an integer >= 1")
        need(self.rival_max_points >= 10, "rival_max_points", "an integer >= 10")
        need(self.rival_grace >= 0, "rival_grace", "an integer >= 0")
        need(self.rival_period >= 1, "rival_period", "an integer >= 1")
        need(self.rival_budget >= 1, "rival_budget", "an integer >= 1")


@dataclass(frozen=True, slots=True)
class ScanConsistency:
    """How well one scan placed at one pose agrees with the map.

    Attributes
    ----------
    fraction : float
        Fraction of valid returning beams whose end point lies within ``tolerance`` of an
        obstacle (0 when there is no such beam).
    n_beams : int
        Valid returning beams considered.
    tolerance : float
        Distance [m] used (``consistency_sigmas * sigma_hit``).
    pose_free : bool
        The pose lies in a free cell of the map.
    points : ndarray of shape (n_beams, 2) or None
        The beams' end points in the robot frame [m] (evidence for the rival search).
    """

    fraction: float
    n_beams: int
    tolerance: float
    pose_free: bool = True
    points: FloatArray | None = None


@dataclass(frozen=True, slots=True)
class Confidence:
    """The verdict for one filter state.

    Attributes
    ----------
    confident : bool
        All checks passed (see the module docstring).
    reason : str
        Why (the first failed check, or a summary when confident).
    checks_pass : bool
        Checks 1-3 and the jump check passed at this update.
    streak : int
        Consecutive scan-integrating updates at which they passed (0 after a failure).
    weight_share : float
        Weight of the heaviest cluster.
    std_xy : float
        Its position standard deviation [m].
    std_theta : float
        Its heading standard deviation [rad].
    scan_consistency : float
        Fraction of agreeing beams at the estimate (NaN when not measured).
    n_beams : int
        Beams in that fraction.
    estimate : ndarray of shape (3,)
        The assessed estimate (map frame).
    odom : ndarray of shape (3,) or None
        The odometry pose at that update (for the jump check of the next one).
    unique : bool
        Check 5 found no rival place on the current track (or is switched off): the place
        was proven unique and the filter has followed it since.
    rival_due : bool
        Checks 1-4 pass but the place has not been shown unique, and a rival search is due
        now: the caller should run it and assess again with its report.
    rival_streak : int
        Streak value at the last rival search of this streak (0: none yet).
    rival : RivalReport or None
        The last rival search of this streak.
    rival_searches : int
        Rival searches run during the current streak.
    locally_confident : bool
        Checks 1-4 hold (the filter tracks a pose that fits the map, sustained) whatever
        check 5 says: the verdict for a caller that resolves place ambiguity itself (the
        localizer, after vision picked the symmetric copy), and what a nav2 user could get.
    track : int
        Breaks of the filter's track since the judgement started: it grows when the estimate
        jumps away from the odometry's prediction, the heaviest cluster loses its share (a new
        cluster) or more than ``rival_grace`` updates in a row fail (a doubt). A place proven
        unique holds while the track is the same.
    doubts : int
        Failed scan-integrating updates in a row on the current track.
    proven : int
        Scan-integrating updates since the place was proven unique on this track (-1: not
        proven on it).
    """

    confident: bool
    reason: str
    checks_pass: bool
    streak: int
    weight_share: float
    std_xy: float
    std_theta: float
    scan_consistency: float
    n_beams: int
    estimate: FloatArray
    odom: FloatArray | None = None
    unique: bool = False
    rival_due: bool = False
    rival_streak: int = 0
    rival: RivalReport | None = None
    locally_confident: bool = False
    rival_searches: int = 0
    track: int = 0
    doubts: int = 0
    proven: int = -1


def hypothesis_std(covariance: ArrayLike) -> tuple[float, float]:
    """Position std [m] (sqrt of the largest x-y eigenvalue) and heading std [rad] of a
    ``(3, 3)`` covariance."""
    c = np.asarray(covariance, dtype=np.float64)
    if c.shape != (3, 3) or not np.all(np.isfinite(c)):
        raise ConfigurationError(f"covariance: expected a finite (3, 3) array, got {c.shape}")
    # the larger eigenvalue of the symmetric 2 x 2 block, in closed form
    a, d, b = float(c[0, 0]), float(c[1, 1]), 0.5 * (float(c[0, 1]) + float(c[1, 0]))
    top = 0.5 * (a + d) + math.hypot(0.5 * (a - d), b)
    return math.sqrt(max(top, 0.0)), math.sqrt(max(float(c[2, 2]), 0.0))


def scan_consistency(
    field: DistanceField,
    pose: ArrayLike,
    scan: LaserScan,
    *,
    sigma_hit: float = 0.2,
    sigmas: float = 2.0,
    laser_pose: ArrayLike = (0.0, 0.0, 0.0),
    laser_max_range: float = -1.0,
    laser_min_range: float = -1.0,
) -> ScanConsistency:
    """Fraction of ``scan``'s valid returning beams that end near an obstacle seen from ``pose``.

    Parameters
    ----------
    field : DistanceField
        The map's distance field (clipped at ``max_dist``; off the map reads ``max_dist``).
    pose : array of shape (3,)
        Robot pose x [m], y [m], theta [rad] in the map frame.
    scan : LaserScan
        Every beam is used (no ``max_beams`` sub-sampling); beams are cleaned as nav2 does
        (:func:`~symloc.mcl.beams.select_beams`): NaN dropped, no-return beams ignored.
    sigma_hit : float
        The laser model's hit noise [m] (> 0).
    sigmas : float
        Tolerance in units of ``sigma_hit``; must stay below ``field.max_dist``.
    laser_pose : array of shape (3,)
        The laser in the robot frame.
    laser_max_range, laser_min_range : float
        nav2's range overrides [m] (<= 0: the scan's own).
    """
    p = np.asarray(pose, dtype=np.float64)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ConfigurationError(f"pose: expected finite shape (3,) x, y, theta, got {p}")
    if not (math.isfinite(sigma_hit) and sigma_hit > 0.0):
        raise ConfigurationError(f"sigma_hit: expected a value > 0 m, got {sigma_hit!r}")
    tol = float(sigmas) * float(sigma_hit)
    if not (tol > 0.0 and tol < field.max_dist):
        raise ConfigurationError(
            f"sigmas * sigma_hit: expected a tolerance in (0, laser_likelihood_max_dist ="
            f" {field.max_dist} m), got {tol!r} m"
        )
    beams = select_beams(
        scan,
        max(len(scan), 2),
        laser_max_range=laser_max_range,
        laser_min_range=laser_min_range,
    )
    grid = field.grid
    cell = grid.world_to_cell(p[None, :2])
    # one cell's free test (grid.free_mask would build the whole map's mask on every scan)
    free = bool(grid.in_bounds(cell)[0]) and bool(grid.is_free(grid.data[cell[0, 0], cell[0, 1]]))
    r, a = beams.ranges[beams.hit], beams.angles[beams.hit]
    if r.size == 0:
        return ScanConsistency(0.0, 0, tol, free, np.zeros((0, 2)))
    lpose = np.asarray(laser_pose, dtype=np.float64)
    local = np.column_stack([r * np.cos(a), r * np.sin(a)])
    robot_pts = transform_points(lpose, local)
    world = transform_points(p, robot_pts)
    d = field.lookup(world)
    frac = float(np.count_nonzero(d <= tol)) / r.size
    return ScanConsistency(frac, int(r.size), tol, free, robot_pts)


def assess(
    result: Any,
    consistency: ScanConsistency | None,
    config: ConfidenceConfig | None = None,
    *,
    previous: Confidence | None = None,
    odom: ArrayLike | None = None,
    rival: RivalReport | None = None,
) -> Confidence:
    """Assess one filter result; chain ``previous`` for the hysteresis.

    Parameters
    ----------
    result : AmclResult
        Anything with ``estimate (3,)``, ``covariance (3, 3)``, ``hypotheses`` (heaviest
        first, each with ``weight``), ``updated`` and ``sensor_skipped``.
    consistency : ScanConsistency or None
        :func:`scan_consistency` of this update's scan at ``result.estimate`` (None: not
        measured, which fails check 3).
    config : ConfidenceConfig, optional
    previous : Confidence, optional
        The verdict of the previous call on the same filter (None after an initialisation).
    odom : array of shape (3,), optional
        Odometry pose of this update; with ``previous.odom`` it enables the jump check.
    rival : RivalReport, optional
        A rival search for this update (run it when a first call returned ``rival_due``).

    Returns
    -------
    Confidence
    """
    cfg = ConfidenceConfig() if config is None else config
    if not isinstance(cfg, ConfidenceConfig):
        raise ConfigurationError(f"config: expected a ConfidenceConfig, got {type(cfg).__name__}")
    est = np.asarray(result.estimate, dtype=np.float64).copy()
    od = None if odom is None else np.asarray(odom, dtype=np.float64).copy()
    if od is not None and (od.shape != (3,) or not np.all(np.isfinite(od))):
        raise ConfigurationError(f"odom: expected finite shape (3,) x, y, theta, got {od}")
    hyps = list(result.hypotheses)
    share = float(hyps[0].weight) if hyps else 1.0
    sxy, sth = hypothesis_std(result.covariance)
    frac = math.nan if consistency is None else float(consistency.fraction)
    nb = 0 if consistency is None else int(consistency.n_beams)

    no_scan = not bool(getattr(result, "updated", True)) or bool(
        getattr(result, "sensor_skipped", False)
    )
    if no_scan and previous is not None:
        # No new scan evidence: keep the verdict and the reference pose of the last update.
        return Confidence(
            previous.confident,
            previous.reason,
            previous.checks_pass,
            previous.streak,
            share,
            sxy,
            sth,
            previous.scan_consistency,
            previous.n_beams,
            previous.estimate,
            previous.odom,
            previous.unique,
            False,
            previous.rival_streak,
            previous.rival,
            previous.locally_confident,
            previous.rival_searches,
            previous.track,
            previous.doubts,
            previous.proven,
        )

    # The track: does this update follow the place of the previous one? A jump from the
    # odometry's prediction to another place (farther than rival_min_distance or turned more
    # than rival_min_angle: what the rival search calls another place) or a new cluster
    # breaks it at once; failed checks (a smaller jump among them) after rival_grace updates
    # in a row (a doubt).
    jump: tuple[float, float] | None = None
    elsewhere = False
    if previous is not None and previous.odom is not None and od is not None:
        pred = compose(previous.estimate, relative(previous.odom, od))
        jxy = float(np.hypot(*(est[:2] - pred[:2])))
        jth = abs(float(wrap_angle(est[2] - pred[2])))
        if jxy > cfg.max_jump_xy or jth > cfg.max_jump_theta:
            jump = (jxy, jth)
        elsewhere = jxy > cfg.rival_min_distance or jth > cfg.rival_min_angle
    track = 0 if previous is None else previous.track
    prev_proven = -1 if previous is None else previous.proven
    prev_doubts = 0 if previous is None else previous.doubts

    def fail(reason: str, *, breaks: bool = False) -> Confidence:
        doubts = prev_doubts + 1
        broken = breaks or doubts == cfg.rival_grace + 1  # once per run of failures
        return Confidence(
            False,
            reason,
            False,
            0,
            share,
            sxy,
            sth,
            frac,
            nb,
            est,
            od,
            prev_proven >= 0 and not broken,
            track=track + 1 if broken else track,
            doubts=doubts,
            proven=-1 if broken or prev_proven < 0 else prev_proven + 1,
        )

    if no_scan:
        return fail("no scan integrated since initialisation", breaks=True)
    if share < cfg.min_weight_share:
        return fail(
            f"no dominant hypothesis: heaviest holds {share:.2f} < {cfg.min_weight_share:.2f}",
            breaks=True,
        )
    if sxy > cfg.max_xy_std or sth > cfg.max_theta_std:
        return fail(
            f"hypothesis too wide: std {sxy:.3f} m / {math.degrees(sth):.1f} deg (limits"
            f" {cfg.max_xy_std:.3f} m / {math.degrees(cfg.max_theta_std):.1f} deg)",
            breaks=elsewhere,
        )
    if consistency is None:
        return fail("scan consistency not measured", breaks=elsewhere)
    if not consistency.pose_free:
        return fail("the estimate is not in a free cell of the map", breaks=elsewhere)
    if nb < cfg.min_beams:
        return fail(
            f"too few valid beams for the scan check ({nb} < {cfg.min_beams})", breaks=elsewhere
        )
    if frac < cfg.min_scan_consistency:
        return fail(
            f"scan disagrees with the map: {frac:.2f} of beams within"
            f" {consistency.tolerance:.2f} m of an obstacle (< {cfg.min_scan_consistency:.2f})",
            breaks=elsewhere,
        )
    if jump is not None:
        # reported after checks 1-3; a jump to another place breaks the track whatever
        # they say
        return fail(
            f"estimate jumped {jump[0]:.2f} m / {math.degrees(jump[1]):.1f} deg from the"
            " odometry prediction",
            breaks=elsewhere,
        )
    same = previous is not None and previous.checks_pass
    streak = 1 + (previous.streak if same else 0)  # type: ignore[union-attr]
    proven = prev_proven + 1 if prev_proven >= 0 else -1
    unique = not cfg.rival_check or proven >= 0
    rival_streak = previous.rival_streak if same else 0  # type: ignore[union-attr]
    last_rival = previous.rival if same else None  # type: ignore[union-attr]
    n_searches = previous.rival_searches if same else 0  # type: ignore[union-attr]
    summary = (
        f"share {share:.2f}, std {sxy:.3f} m / {math.degrees(sth):.1f} deg,"
        f" scan {frac:.2f} of {nb} beams, {streak} updates"
    )

    def ok(confident: bool, reason: str, **kw: Any) -> Confidence:
        return Confidence(
            confident,
            reason,
            True,
            streak,
            share,
            sxy,
            sth,
            frac,
            nb,
            est,
            od,
            kw.get("unique", unique),
            kw.get("rival_due", False),
            kw.get("rival_streak", rival_streak),
            kw.get("rival", last_rival),
            streak >= cfg.hold_updates,
            n_searches + (1 if "rival" in kw else 0),
            track,
            0,
            kw.get("proven", proven),
        )

    if streak < cfg.hold_updates:
        return ok(False, f"checks pass for {streak} of {cfg.hold_updates} updates")
    if rival is not None:
        if not rival.ambiguous:
            return ok(
                True,
                f"confident: {summary}; unique (best rival {rival.rival_score:.2f} vs"
                f" {rival.estimate_score:.2f})",
                unique=True,
                rival_streak=streak,
                rival=rival,
                proven=0,
            )
        where = (
            ""
            if rival.rival_pose is None
            else f" at ({rival.rival_pose[0]:.2f}, {rival.rival_pose[1]:.2f},"
            f" {math.degrees(rival.rival_pose[2]):.0f} deg)"
        )
        return ok(
            False,
            f"ambiguous place: a rival pose{where} explains the scans"
            f" {rival.rival_score:.2f} vs {rival.estimate_score:.2f}",
            unique=not cfg.rival_check,
            rival_streak=streak,
            rival=rival,
            proven=-1,
        )
    if unique:
        # proven on this track; searched again every rival_period updates (still confident)
        again = cfg.rival_check and proven >= cfg.rival_period
        return ok(True, f"confident: {summary}", rival_due=again)
    # Back off: wait rival_recheck, then 2x, 4x ... updates (a symmetric room stays ambiguous).
    wait = cfg.rival_recheck * 2 ** max(n_searches - 1, 0)
    due = rival_streak == 0 or streak - rival_streak >= wait
    reason = (
        "rival search due"
        if due
        else f"ambiguous place (searched {streak - rival_streak} updates ago)"
    )
    return ok(False, reason, rival_due=due)


class ConfidenceJudge:
    """The confidence verdict of one :class:`~symloc.mcl.Amcl` filter, judged after each update.

    Owns what the verdict carries from one update to the next: the previous verdict (the
    hysteresis), the scans of the current streak (the rival search's evidence), the map's
    consistency and rival-search fields, and the count of rival searches. A new
    initialisation of the filter (``initialize_global`` / ``initialize_pose``) starts a new
    judgement: the judge notices it (``amcl.counters.n_initializations``) and forgets the
    verdict and the evidence, as if :meth:`reset` had been called at that moment.

    Parameters
    ----------
    amcl : Amcl
        The filter whose results are judged (its ``sigma_hit``, laser range limits and
        map fields are used).
    config : ConfidenceConfig, optional
        Thresholds of the verdict (default :class:`ConfidenceConfig()`).

    Attributes
    ----------
    amcl : Amcl
    config : ConfidenceConfig
    n_rival_searches : int
        Rival searches completed since the judge was made (over every streak and
        initialisation).
    n_rival_dropped : int
        Searches dropped unfinished because the track broke before they ended.
    consistency_field : DistanceField
        The map's distance field the scan check reads: the filter's likelihood field when its
        ``laser_likelihood_max_dist`` exceeds the check's tolerance ``consistency_sigmas *
        sigma_hit``, else the map's field clipped at twice the tolerance.
    """

    def __init__(self, amcl: Amcl, config: ConfidenceConfig | None = None) -> None:
        self.amcl = amcl
        self.config = ConfidenceConfig() if config is None else config
        if not isinstance(self.config, ConfidenceConfig):
            raise ConfigurationError(
                f"config: expected a ConfidenceConfig, got {type(self.config).__name__}"
            )
        self.n_rival_searches = 0
        tol = self.config.consistency_sigmas * amcl.params.sigma_hit
        own = amcl.field
        # The scan check needs distances beyond its tolerance: a wider field if the map's is not.
        self.consistency_field: DistanceField = (
            own if tol < own.max_dist else amcl.fields.distance(2.0 * tol)
        )
        self._verdict: Confidence | None = None
        self._evidence: list[tuple[FloatArray, FloatArray]] = []
        self._init_seen = amcl.counters.n_initializations
        self._run: RivalSearchRun | None = None
        self.n_rival_dropped = 0

    def reset(self) -> None:
        """Forget the verdict, the streak's evidence and a search under way (the filter was
        re-initialised)."""
        self._verdict = None
        self._evidence = []
        self._init_seen = self.amcl.counters.n_initializations
        self._run = None

    @property
    def search(self) -> RivalSearchRun | None:
        """The rival search under way (spread over updates by ``rival_budget``), if any."""
        return self._run

    def _sync(self) -> None:
        if self._init_seen != self.amcl.counters.n_initializations:
            self.reset()

    @property
    def verdict(self) -> Confidence | None:
        """The verdict of the last judged result (None before the first one after an
        initialisation)."""
        self._sync()
        return self._verdict

    def __call__(
        self,
        result: AmclResult,
        odom: OdometryReading,
        scan: LaserScan,
        *,
        laser_pose: ArrayLike = (0.0, 0.0, 0.0),
    ) -> Confidence:
        """Judge ``result``, what ``amcl.update(odom, scan, laser_pose=laser_pose)`` returned.

        Parameters
        ----------
        result : AmclResult
            The filter's last result (judge every one, in order).
        odom : OdometryReading
            The odometry given to that update.
        scan : LaserScan
            The scan given to that update.
        laser_pose : array of shape (3,)
            The laser in the robot frame, as given to that update.

        Returns
        -------
        Confidence
            Also :attr:`verdict` until the next call. When a rival search is due, it advances
            here by at most ``rival_budget`` pose-point pairs (a search of a large map ends a
            few updates later; it is dropped if the track breaks first).
        """
        self._sync()
        amcl, cfg = self.amcl, self.config
        p = amcl.params
        pose = np.asarray(odom.pose, dtype=np.float64)
        cons = None
        if result.updated and not result.sensor_skipped:
            cons = scan_consistency(
                self.consistency_field,
                result.estimate,
                scan,
                sigma_hit=p.sigma_hit,
                sigmas=cfg.consistency_sigmas,
                laser_pose=laser_pose,
                laser_max_range=p.laser_max_range,
                laser_min_range=p.laser_min_range,
            )
        conf = assess(result, cons, cfg, previous=self._verdict, odom=pose)
        if cons is not None:
            if not conf.checks_pass:
                self._evidence.clear()
            elif cons.points is not None:
                self._evidence.append((conf.estimate, cons.points))
                del self._evidence[: -cfg.evidence_updates]
        run = self._run
        if run is not None and run.track != conf.track:
            # the place the search was about is no longer followed: its answer is moot
            self._run = run = None
            self.n_rival_dropped += 1
        if conf.rival_due:
            if run is None:
                self._run = run = RivalSearchRun(self._rival_steps(conf.estimate), track=conf.track)
            rival = run.advance(cfg.rival_budget)
            if rival is not None:
                self._run = None
                conf = assess(result, cons, cfg, previous=self._verdict, odom=pose, rival=rival)
                self.n_rival_searches += 1
            elif not conf.confident:
                conf = dataclasses.replace(
                    conf,
                    reason=f"rival search under way ({run.calls} updates,"
                    f" {run.pairs:,} pose-point pairs so far)",
                )
        self._verdict = conf
        return conf

    def update(
        self,
        odom: OdometryReading,
        scan: LaserScan,
        *,
        laser_pose: ArrayLike = (0.0, 0.0, 0.0),
    ) -> tuple[AmclResult, Confidence]:
        """Run the filter update, then judge it: ``amcl.update(...)`` followed by this judge.

        The convenience of a caller that uses AMCL alone. Returns the filter's result and the
        verdict on it.
        """
        result = self.amcl.update(odom, scan, laser_pose=laser_pose)
        return result, self(result, odom, scan, laser_pose=laser_pose)

    def _evidence_points(self, estimate: FloatArray) -> FloatArray:
        """The scans of the current streak chained into the estimate's frame, ``(M, 2)`` [m]."""
        pts = [transform_points(relative(estimate, est_k), p_k) for est_k, p_k in self._evidence]
        return np.concatenate(pts) if pts else np.zeros((0, 2))

    def _rival_steps(self, estimate: FloatArray) -> Generator[int, None, RivalReport]:
        """The rival search on the scans of the current streak, chained into the estimate's
        frame, as slices of at most ``rival_budget`` pose-point pairs."""
        cfg = self.config
        points = self._evidence_points(estimate)
        field = self.amcl.fields.grown(self.consistency_field.max_dist)
        return rival_search_steps(
            field,
            points,
            estimate,
            tol=cfg.rival_tolerance_sigmas * self.amcl.params.sigma_hit,
            min_distance=cfg.rival_min_distance,
            min_angle=cfg.rival_min_angle,
            margin=cfg.rival_margin,
            max_points=cfg.rival_max_points,
            chunk_pairs=min(cfg.rival_budget, 1 << 22),
        )
