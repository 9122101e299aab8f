"""The localizer's settings: one frozen dataclass that validates itself (metres, radians, counts)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from symloc._checks import check_in_range, check_positive
from symloc.errors import ConfigurationError

__all__ = ["LocalizerConfig"]


@dataclass(frozen=True, slots=True)
class LocalizerConfig:
    """Settings of the localizer (units: m, rad, counts).

    Whether AMCL converged is the tracker's own verdict (``TrackerResult.confident``,
    :mod:`symloc.mcl.confidence`); the localizer only asks for it ``converged_updates`` times
    in a row.

    Attributes
    ----------
    min_cluster_weight : a cluster is a hypothesis when its weight is at least this.
    converged_updates : consecutive converged updates before the pose is earned.
    symmetry_position_tol, symmetry_angle_tol : how close a cluster must be to a rotated copy of
        the heaviest one to count as its symmetric image [m], [rad].
    copy_score_ratio : with a pose scorer, a rotated copy whose score is at least this fraction
        of the estimate's own score explains the scan as well (the ambiguity is real).
    copy_claim_floor : a rotated copy whose aligned fit reaches the claim gate's
        ``min_claim_fit`` explains the scan as well, whatever the estimate's own fit
        (:class:`~symloc.localizer.copies.CopyRule`). Off by default: on the dev split
        (t_shape, furnished, l_shape) ``copy_map_slack`` alone removes the same lie and the
        floor halves l_shape's correct claims (17 -> 9 of 20).
    copy_map_slack : a rotated copy whose share of beams within this distance [m] of the walls
        (aligned) is at least ``copy_score_ratio`` x the estimate's explains the scan as well: a
        map off by up to this much near a wall costs the truth its beams there (0: off).
    place_radius_factor : a known place covers the disc of radius factor x its G-V distance.
    centre_smoothing : weight of a new per-scan centre estimate (:class:`CentreFilter`).
    centre_tolerance : the robot has reached the centre when the scan's centre is this close [m].
    facing_tolerance : facing done when the bearing to the corner-middle is below this [rad].
    rotate_tolerance : a ROTATE request is done when odometry turned within this [rad].
    flip_patience : consecutive non-symmetric verdicts before the trip to the centre is dropped.
    max_centering_updates : updates allowed for going to the centre and facing.
    relocalize_after : consecutive filter updates, while lost, at which the scan contradicts
        AMCL's estimate before AMCL is spread over the whole map again (a kidnapped robot's
        particles may all be in the wrong place, and nav2's filter has no recovery by default).
    allow_mapping : build a visual map for a place that matches nothing (Algorithm 5 step 11).
    reseed_xy_std, reseed_theta_std : smallest spread of the AMCL reseed after a decision.
    decision_xy_std, decision_theta_std : how well a visual decision knows the pose before the
        laser sets it (the stored centre's and the decided heading's std) [m], [rad].
    decide_here : decide from where the robot stands (:mod:`symloc.localizer.decide_here`):
        while the pose is not earned, the laser proposes hypotheses (AMCL's clusters, the global
        scan-to-map search, rotated copies about the map's and the known places' symmetries)
        and the camera verifies them against the visual map's keyframes; the drive to the
        centre is the last resort. On by default (off: the paper's path alone, Algorithms 2-5).
    decide_min_fit : least share of beams a hypothesis explains (after the laser aligned it).
    decide_laser_margin : a hypothesis survives the laser when its share of beams is within
        this of the best one's (a rotated copy of the best also when the copy check would not
        rule it out); exactly one survivor is handed to AMCL and the copy checks.
    decide_views : images asked for from where the robot stands before giving up.
    decide_turn : least angle [rad] between the headings of two views (the view planner,
        :mod:`symloc.localizer.view_planning`, turns to where the keyframes are).
    decide_turn_tolerance : a turn to a view is done when odometry turned within this [rad]
        of it. The keyframes the plan counted lie within
        ``VerificationSettings.max_heading_difference`` (40 deg) of the heading turned to, and
        the hypotheses are carried to the image's moment whatever heading it was taken at,
        while a turn controller slowing down in proportion to the angle left
        (:mod:`symloc.localizer.centering`: 1.5 / s) spends most of a turn on its last
        degrees: 1.7 s of a 60 deg turn to reach 3 deg (``rotate_tolerance``), 0.9 s to reach
        10 deg.
    axis_max_turn : a withheld claim is reported as an axis estimate
        (:mod:`symloc.localizer.withheld_axis`) only from scans taken while odometry turns
        slower than this [rad/s]: a sweep is deskewed with the odometry's turn, which slips on
        turns, and the gate's heading std does not know it (the heavy test split,
        t_shape#1000001 #5: 3-6 deg off at 0.7 rad/s with a std of 0.6-1.2 deg).
    operator_image_wait : scans the first claim at the operator's pose waits for the image
        asked for where a rotated copy explains the scan as well
        (:mod:`symloc.localizer.operator_veto`); without one the operator's choice stands (0: no
        image is asked for).
    decide_theta_std : how well a verified hypothesis' heading is known before the laser
        sets it [rad] (its position: ``decision_xy_std``).
    decide_round_reach : on a round map (the claim gate's ``rotation_centre``) the survivors
        are one family of poses turned about the centre, and a heading error costs the
        distance from the centre times as much in position: a claim decided 2.5-3 m from the
        centre with a heading known to 0.6 deg (the camera's, measured again) is 2.6-3.1 cm
        along the wall, beyond the gate's 2.5 cm, and odometry carries the withheld pose's
        heading off by 5 % of every turn on the way in (dev circle#1, realistic sensors: every
        such decision withheld, the carried heading 3 deg off after 4 s). So deciding here on
        a round map first drives (``GO_TO``, at travelling speed) to within this distance [m]
        of the centre (the laser finds it in the robot's frame: every survivor puts it in the
        same place), where 1 deg of heading is 0.9 cm.
    decide_max_hypotheses : most hypotheses aligned and shown to the camera (best first).
    decide_rest : scans left to the other phases (AMCL's convergence, the drive to the centre)
        after deciding here handed over or gave up, before it is tried again.
    decide_rest_no_camera : the same without keyframes (a laser-only robot): AMCL converging
        is then the only other phase and it runs at every scan anyway, so a fresh scan's
        proposal is worth a global search sooner (amcl-carmen on aces at seed 1: in 12 of 20
        starts deciding here gave up at the first scan, and the 100 scans of ``decide_rest``
        were the whole window, lost to its end). Not tuned: a fifth of ``decide_rest``.
    decide_watch_evidence : without keyframes, the laser watches several surviving hypotheses
        as the robot moves (:mod:`symloc.localizer.laser_watch`); a rival is ruled out when
        its deficit of beams explained against the leader, summed over new views (less 1 %
        per view), reaches this share of a scan (for the beams within the match's distance
        and within ``copy_map_slack`` alike).
    decide_watch_views : views watched without a decision before deciding here gives up.
    axis_max_spread : the laser's hypotheses are an axis family (a corridor: heading known up to
        a half turn, position along a line not; :mod:`symloc.localizer.axis`) when each lies
        within this [m] of its heading class' line ...
    axis_heading_spread : ... with headings within this [rad] of their class' mean ...
    axis_min_length : ... and one class spans at least this [m] along the line.
    axis_sweep_ratio : along the line, the scan fits where the pose scorer gives at least this
        share of the line's best score (the segment's extent).
    axis_continuity : ... and it must fit along at least this share of that stretch (a
        corridor: all of it; repeated features such as pillars leave gaps, and their poses are
        shown to the camera one by one as anywhere else).
    axis_open_reach : an end of the segment where the line runs into space the map does not
        cover is lengthened by this [m] beyond the map (the passage may go on unmapped).
    axis_spacing, axis_max_hypotheses : the hypotheses shown to the camera along each heading
        class' segment: this far apart [m], at most this many per class.
    axis_min_inliers : the winning heading class' best verified hypothesis needs at least this
        many inliers, and the camera's verification margin over the other class' best fit
        (one weak match never decides the heading).
    axis_views : images, taken at headings at least ``decide_turn`` apart, that must each
        decide the same heading class (and none the other) before the axis is reported: on
        the dev split one image matched the half-turned class with 31-36 inliers where the
        robot stood in the corridor's unmapped half.
    axis_across_std, axis_theta_std : least std [m], [rad] of the axis estimate across the axis
        and in heading.
    axis_line_std : std [rad] of the axis' direction where it runs far from the stretch it was
        fitted on (a SLAM map bends a little over tens of metres); it widens the estimate
        across the axis in proportion to the segment's reach.
    axis_odometry : the segment lengthens at each end by this share of the distance travelled
        (odometry's error along the axis).
    axis_pin_step, axis_pin_apart, axis_pin_gain : an axis family whose ends the scan sees is
        one pose per heading class (:mod:`symloc.localizer.axis_pin`): the whole scan's fit is
        profiled every ``axis_pin_step`` [m] along each class' line, and the class is pinned
        where it fits best when that fit is at least ``axis_pin_gain`` (a share) lower than
        anywhere farther than ``axis_pin_apart`` [m] from there; the default is the measured
        :data:`symloc.localizer.axis_pin.PIN_GAIN` (0.25), 1 turns it off (it was off from
        37b875e to 08b4924, after heavy sensors made it claim a short corridor 10-11 cm off:
        README, "The walls' shared error in the claim gate" and "The heavy dev lies, traced").
    axis_recheck : scans on the axis between two tries of deciding here (the laser proposes
        again, the camera looks when an end, a door or a keyframe could pin the position).
    axis_patience : scans in a row at which the laser does not confirm the axis (the scan no
        longer fits the line with the decided heading) before it is given up.
    precision_drive : while a claim is withheld only because the map's scale error
        (``ClaimConfig.map_scale_std``, which grows with the distance from the map's middle) makes
        it too imprecise, ask the driver to go where that error vanishes (a ``GO_TO``
        request towards :meth:`~symloc.localizer.claim.ClaimGate.precise_place`); the claim is
        published from the first scan that passes on the way. False: no request (a lost robot
        turns on the spot, an axis estimate stands). On the dev split (realistic sensors) 28 of
        the 30 undetermined trials outside circles and long corridors ended so, 2.9-6.7 cm std
        along one axis; with the drive 210 -> 222 of 280 correct, 0 wrong, the slowest tenth of
        the first claims 25.7 -> 14.0 s. Short corridors gained one: half-way to the middle the
        end walls are too far for the match to pin the position along the corridor.
    precision_clearance : that place keeps at least this far [m] from every obstacle the map
        has (the robot's radius and a margin).
    precision_lookahead : the request's target is this far [m] along the route through free
        space (:class:`~symloc.localizer.precision_route.FreeRoute`), so that a straight drive
        to it does not cut a corner.
    """

    min_cluster_weight: float = 0.05
    converged_updates: int = 3
    symmetry_position_tol: float = 0.35
    symmetry_angle_tol: float = math.radians(15.0)
    copy_score_ratio: float = 0.9
    copy_claim_floor: bool = False
    copy_map_slack: float = 0.3
    place_radius_factor: float = 1.2
    centre_tolerance: float = 0.01
    facing_tolerance: float = math.radians(1.5)
    rotate_tolerance: float = math.radians(3.0)
    flip_patience: int = 5
    max_centering_updates: int = 600
    relocalize_after: int = 100
    allow_mapping: bool = False
    reseed_xy_std: float = 0.03
    reseed_theta_std: float = math.radians(2.0)
    decision_xy_std: float = 0.15
    decision_theta_std: float = math.radians(2.0)
    centre_smoothing: float = 0.5
    decide_here: bool = True
    decide_min_fit: float = 0.6
    decide_laser_margin: float = 0.15
    decide_views: int = 4
    decide_turn: float = math.radians(45.0)
    decide_turn_tolerance: float = math.radians(10.0)
    decide_theta_std: float = math.radians(5.0)
    operator_image_wait: int = 3
    axis_max_turn: float = 0.25
    decide_max_hypotheses: int = 16
    decide_round_reach: float = 0.5
    decide_rest: int = 100
    decide_rest_no_camera: int = 20
    decide_watch_evidence: float = 0.5
    decide_watch_views: int = 40
    axis_max_spread: float = 0.2
    axis_heading_spread: float = math.radians(10.0)
    axis_min_length: float = 1.0
    axis_sweep_ratio: float = 0.7
    axis_continuity: float = 0.8
    axis_open_reach: float = 40.0
    axis_spacing: float = 1.0
    axis_max_hypotheses: int = 24
    axis_min_inliers: int = 30
    axis_views: int = 2
    axis_across_std: float = 0.05
    axis_theta_std: float = math.radians(1.0)
    axis_line_std: float = math.radians(0.3)
    axis_odometry: float = 0.05
    axis_pin_step: float = 0.05
    axis_pin_apart: float = 0.5
    axis_pin_gain: float = 0.25  # axis_pin.PIN_GAIN; 1 turns it off
    axis_recheck: int = 30
    axis_patience: int = 30
    precision_drive: bool = True
    precision_clearance: float = 0.4
    precision_lookahead: float = 0.5

    def __post_init__(self) -> None:
        for name in (
            "symmetry_position_tol",
            "symmetry_angle_tol",
            "place_radius_factor",
            "centre_tolerance",
            "facing_tolerance",
            "rotate_tolerance",
            "reseed_xy_std",
            "reseed_theta_std",
            "decision_xy_std",
            "decision_theta_std",
            "decide_turn",
            "decide_turn_tolerance",
            "decide_round_reach",
            "axis_max_turn",
            "decide_theta_std",
            "decide_watch_evidence",
            "axis_max_spread",
            "axis_heading_spread",
            "axis_min_length",
            "axis_spacing",
            "axis_across_std",
            "axis_theta_std",
            "axis_line_std",
            "precision_clearance",
            "precision_lookahead",
        ):
            check_positive(getattr(self, name), f"LocalizerConfig.{name}")
        check_in_range(self.min_cluster_weight, "LocalizerConfig.min_cluster_weight", 0.0, 1.0)
        check_in_range(self.centre_smoothing, "LocalizerConfig.centre_smoothing", 1e-6, 1.0)
        check_in_range(self.copy_score_ratio, "LocalizerConfig.copy_score_ratio", 0.0, 1.0)
        check_in_range(self.decide_min_fit, "LocalizerConfig.decide_min_fit", 0.0, 1.0)
        check_in_range(self.decide_laser_margin, "LocalizerConfig.decide_laser_margin", 0.0, 1.0)
        check_in_range(self.axis_sweep_ratio, "LocalizerConfig.axis_sweep_ratio", 0.0, 1.0)
        check_in_range(self.axis_continuity, "LocalizerConfig.axis_continuity", 0.0, 1.0)
        check_positive(self.axis_pin_step, "LocalizerConfig.axis_pin_step")
        check_positive(self.axis_pin_apart, "LocalizerConfig.axis_pin_apart")
        check_in_range(self.axis_pin_gain, "LocalizerConfig.axis_pin_gain", 0.0, 1.0)
        check_positive(self.axis_open_reach, "LocalizerConfig.axis_open_reach", allow_zero=True)
        check_positive(self.axis_odometry, "LocalizerConfig.axis_odometry", allow_zero=True)
        check_positive(self.copy_map_slack, "LocalizerConfig.copy_map_slack", allow_zero=True)
        for flag in ("decide_here", "copy_claim_floor", "precision_drive"):
            if not isinstance(getattr(self, flag), bool):
                raise ConfigurationError(
                    f"LocalizerConfig.{flag}: expected a bool, got {getattr(self, flag)!r}"
                )
        for name in (
            "converged_updates",
            "flip_patience",
            "max_centering_updates",
            "relocalize_after",
            "decide_views",
            "decide_max_hypotheses",
            "decide_rest",
            "decide_rest_no_camera",
            "decide_watch_views",
            "axis_max_hypotheses",
            "axis_min_inliers",
            "axis_views",
            "axis_recheck",
            "axis_patience",
        ):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ConfigurationError(
                    f"LocalizerConfig.{name}: expected an integer >= 1, got {value!r}"
                )
        wait = self.operator_image_wait
        if not isinstance(wait, int) or isinstance(wait, bool) or wait < 0:
            raise ConfigurationError(
                f"LocalizerConfig.operator_image_wait: expected an integer >= 0 (0: never "
                f"asked), got {wait!r}"
            )
