"""State-machine tests of the Localizer with scripted collaborators (no simulator)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.geometry import angle_diff, compose, inverse, wrap_angle
from symloc.localizer import (
    Decision,
    Estimate,
    Hypothesis,
    Localizer,
    LocalizerConfig,
    Place,
    Request,
    RequestKind,
    Status,
    SymmetryVerdict,
    TrackerResult,
    rotated_copies,
    symmetry_consistent,
)
from symloc.localizer.copies import CIRCLE_SAMPLES
from symloc.odometry import OdometryReading
from symloc.symmetry.order import SymmetryOrder

# These tests follow the paper's path (Algorithms 2-5); deciding where the robot stands
# (the default) is tested in test_localizer_decide_here.py.
PAPER = LocalizerConfig(decide_here=False)
CENTRE = np.array([2.0, 1.0])
HALF = 1.5  # square room of side 3 m


def _result(poses, weights, std=0.05) -> TrackerResult:
    hyps = tuple(
        Hypothesis(pose=np.asarray(p, float), weight=w)
        for p, w in sorted(zip(poses, weights, strict=True), key=lambda pw: -pw[1])
    )
    cov = np.diag([std**2, std**2, math.radians(2) ** 2])
    # the tracker's own verdict, as AMCL's adapter gives it: one heavy, tight cluster
    confident = hyps[0].weight >= 0.9 and std <= 0.15
    return TrackerResult(
        estimate=hyps[0].pose, covariance=cov, hypotheses=hyps, confident=confident
    )


@dataclass
class FakeTracker:
    """AMCL stand-in: returns a scripted result, or one cluster at a reseeded pose."""

    script: list[TrackerResult] = field(default_factory=list)
    default: TrackerResult | None = None
    seeded: list[np.ndarray] = field(default_factory=list)
    globals_: int = 0

    def initialize_global(self) -> None:
        self.globals_ += 1

    def initialize_pose(self, pose, covariance) -> None:
        self.seeded.append(np.asarray(pose, float))
        self.default = _result([pose], [1.0])

    def force_update(self) -> None:
        pass

    def update(self, odom, scan) -> TrackerResult:
        if self.script:
            return self.script.pop(0)
        assert self.default is not None
        return self.default


class SquareJudge:
    """Judges the scan of a square room from the robot's true pose (the scan is the pose)."""

    def __init__(self, symmetric: bool = True) -> None:
        self.symmetric = symmetric
        self.flip: list[bool] = []

    def __call__(self, scan) -> SymmetryVerdict:
        sym = self.flip.pop(0) if self.flip else self.symmetric
        if not sym:
            return SymmetryVerdict(
                False, SymmetryOrder.finite(1), "asymmetric", None, float("nan"), reason="test"
            )
        pose = scan
        c = compose(inverse(pose), np.array([*CENTRE, 0.0]))[:2]
        # wall middles of the square, as bearings in the base frame
        mids = CENTRE + HALF * np.array([[1, 0], [0, 1], [-1, 0], [0, -1]], float)
        rel = compose(inverse(pose), np.column_stack([mids, np.zeros(4)]))
        bearings = np.arctan2(rel[:, 1] - c[1], rel[:, 0] - c[0])
        facing = float(bearings[np.argmin(np.abs(bearings))])
        return SymmetryVerdict(
            True, SymmetryOrder.finite(4), "polygon", c, HALF * math.sqrt(2), facing=facing
        )


@dataclass
class FakeStore:
    places: list[Place] = field(default_factory=list)
    decisions: list[Decision] = field(default_factory=list)
    added: list[tuple] = field(default_factory=list)
    headings: list[list[float] | None] = field(default_factory=list)

    def candidates(self, gv_distance, order):
        return [p for p in self.places if abs(p.gv_distance - gv_distance) < 0.05]

    def decide(self, place, image) -> Decision:
        return self.decisions.pop(0) if self.decisions else Decision("refused", reason="empty")

    def add_place(self, center, heading0, order, gv_distance, kind, images, headings=None) -> Place:
        self.added.append((center, heading0, order, gv_distance, kind, len(images)))
        self.headings.append(None if headings is None else list(headings))
        k = 0 if order.is_circle else order.k  # Place.order: 0 for a circle
        p = Place(len(self.places), np.asarray(center), heading0, len(images), k, gv_distance)
        self.places.append(p)
        return p


PLACE = Place(7, CENTRE.copy(), heading0=0.3, m=4, order=4, gv_distance=HALF * math.sqrt(2))


class Driver:
    """Carries out requests exactly (a perfect robot), feeding odometry = true pose."""

    def __init__(self, loc: Localizer, pose) -> None:
        self.loc = loc
        self.pose = np.asarray(pose, float)
        self.history: list[Estimate] = []

    def step(self, image=None) -> Estimate:
        est = self.loc.update(OdometryReading(self.pose.copy()), self.pose.copy(), image)
        self.history.append(est)
        return est

    def act(self, req: Request | None) -> np.ndarray | None:
        if req is None:
            return None
        if req.kind is RequestKind.GO_TO_CENTRE:
            t = req.target
            d = float(np.hypot(*t))
            move = min(d, 0.2)
            heading = math.atan2(t[1], t[0])
            self.pose = compose(self.pose, [move * math.cos(heading), move * math.sin(heading), 0])
        elif req.kind in (RequestKind.FACE_DIRECTION, RequestKind.ROTATE):
            turn = float(np.clip(req.angle, -0.5, 0.5))
            self.pose = compose(self.pose, [0.0, 0.0, turn])
        elif req.kind is RequestKind.CAPTURE_IMAGE:
            return np.full((4, 4, 3), 128, np.uint8)
        return None

    def run(self, n: int) -> Estimate:
        est = self.step()
        for _ in range(n):
            image = self.act(est.request)
            est = self.step(image)
            if est.request is None:
                break
        return est


def _ambiguous_tracker(true_pose) -> FakeTracker:
    copies = rotated_copies(np.asarray(true_pose, float), CENTRE, SymmetryOrder.finite(4))
    return FakeTracker(default=_result(copies, [0.25] * 4))


def test_converged_in_asymmetric_place_is_earned_after_n_updates():
    tracker = FakeTracker(default=_result([[0.5, 0.5, 0.1]], [1.0]))
    loc = Localizer(tracker, SquareJudge(symmetric=False), FakeStore(), PAPER)
    statuses = [loc.update(OdometryReading(np.zeros(3)), None).status for _ in range(3)]
    assert statuses == [Status.LOST, Status.LOST, Status.TRACKING]
    est = loc.update(OdometryReading(np.zeros(3)), None)
    assert est.status is Status.TRACKING
    np.testing.assert_allclose(est.pose, [0.5, 0.5, 0.1])


def test_not_converged_is_lost_without_pose():
    tracker = FakeTracker(default=_result([[0, 0, 0], [1, 1, 1]], [0.5, 0.5], std=1.0))
    loc = Localizer(tracker, SquareJudge(symmetric=False), FakeStore(), PAPER)
    est = loc.update(OdometryReading(np.zeros(3)), None)
    assert est.status is Status.LOST
    assert est.pose is None


def test_full_resolution_path_goes_to_centre_faces_decides_and_reseeds():
    true = np.array([2.8, 0.4, 2.0])
    tracker = _ambiguous_tracker(true)
    store = FakeStore(places=[PLACE], decisions=[Decision("decided", 2, math.radians(3), 0.9)])
    loc = Localizer(tracker, SquareJudge(), store, PAPER)
    drv = Driver(loc, true)
    first = drv.step()
    assert first.status is Status.AMBIGUOUS
    assert first.order == SymmetryOrder.finite(4)
    assert len(first.hypotheses) == 4
    assert first.pose is None
    assert first.request is not None
    assert first.request.kind is RequestKind.GO_TO_CENTRE
    final = drv.run(200)
    kinds = [e.request.kind for e in drv.history if e.request is not None]
    assert RequestKind.FACE_DIRECTION in kinds
    assert RequestKind.CAPTURE_IMAGE in kinds
    statuses = {e.status for e in drv.history}
    assert {Status.GOING_TO_CENTRE, Status.DECIDING} <= statuses
    assert all(e.pose is None for e in drv.history[:-1])
    assert final.status is Status.TRACKING
    expected = wrap_angle(0.3 - 2 * math.pi / 4 * 2 + math.radians(3))
    np.testing.assert_allclose(final.pose[:2], CENTRE)
    assert abs(angle_diff(final.pose[2], expected)) < 1e-9
    assert len(tracker.seeded) == 1
    # afterwards it tracks from the reseeded filter
    assert drv.step().status is Status.TRACKING


def test_undetermined_turns_clockwise_by_360_over_m_then_decides():
    true = np.array([2.3, 1.2, 0.2])
    store = FakeStore(
        places=[PLACE],
        decisions=[Decision("undetermined", reason="ratio"), Decision("decided", 1, 0.0, 0.8)],
    )
    loc = Localizer(_ambiguous_tracker(true), SquareJudge(), store, PAPER)
    drv = Driver(loc, true)
    final = drv.run(300)
    rotates = [e.request for e in drv.history if e.request and e.request.kind is RequestKind.ROTATE]
    assert rotates
    assert rotates[0].angle == pytest.approx(-math.pi / 2)
    assert final.status is Status.TRACKING


def test_featureless_images_end_ambiguous_undetermined_never_a_pose():
    true = np.array([1.2, 0.0, -1.0])
    store = FakeStore(places=[PLACE], decisions=[Decision("refused", reason="12 keypoints")] * 4)
    loc = Localizer(_ambiguous_tracker(true), SquareJudge(), store, PAPER)
    drv = Driver(loc, true)
    final = drv.run(400)
    assert final.status is Status.AMBIGUOUS
    assert final.pose is None
    assert "too few features" in final.reason
    assert all(e.status is not Status.TRACKING for e in drv.history)
    captures = [e for e in drv.history if e.request and e.request.kind is RequestKind.CAPTURE_IMAGE]
    assert len({id(e) for e in captures}) >= 4
    assert loc.phase == "settled"


def test_no_match_with_mapping_allowed_builds_a_new_place_and_says_so():
    true = np.array([2.5, 2.0, 0.7])
    store = FakeStore(places=[])  # nothing with this G-V distance
    loc = Localizer(
        _ambiguous_tracker(true),
        SquareJudge(),
        store,
        LocalizerConfig(decide_here=False, allow_mapping=True),
    )
    drv = Driver(loc, true)
    final = drv.run(600)
    assert len(store.added) == 1
    _centre, _h0, order, _gv, _kind, n_images = store.added[0]
    assert order == SymmetryOrder.finite(4)
    assert n_images == 4
    assert final.status is Status.AMBIGUOUS
    assert "new visual map" in final.reason
    assert final.pose is None


def test_no_match_without_mapping_is_undetermined():
    true = np.array([2.5, 2.0, 0.7])
    store = FakeStore(places=[PLACE], decisions=[Decision("no_match", reason="low")] * 4)
    loc = Localizer(_ambiguous_tracker(true), SquareJudge(), store, PAPER)
    final = Driver(loc, true).run(600)
    assert final.status is Status.AMBIGUOUS
    assert "no visual map matches" in final.reason
    assert store.added == []


def test_symmetric_verdict_that_flips_back_abandons_the_trip_and_is_lost():
    true = np.array([2.9, 0.1, 0.0])
    judge = SquareJudge()
    judge.flip = [True] + [False] * 10
    tracker = _ambiguous_tracker(true)
    loc = Localizer(
        tracker, judge, FakeStore(), LocalizerConfig(decide_here=False, flip_patience=3)
    )
    drv = Driver(loc, true)
    first = drv.step()
    assert first.status is Status.AMBIGUOUS
    statuses = []
    est = first
    for _ in range(4):
        drv.act(est.request)
        est = drv.step()
        statuses.append(est.status)
    assert statuses[:2] == [Status.GOING_TO_CENTRE, Status.GOING_TO_CENTRE]
    assert statuses[2] is Status.LOST
    assert est.pose is None


def test_a_single_spurious_verdict_keeps_going_on_odometry():
    true = np.array([2.9, 0.1, 0.0])
    judge = SquareJudge()
    judge.flip = [True, False, True, False]
    loc = Localizer(
        _ambiguous_tracker(true),
        judge,
        FakeStore(),
        LocalizerConfig(decide_here=False, flip_patience=3),
    )
    drv = Driver(loc, true)
    est = drv.step()
    for _ in range(4):
        drv.act(est.request)
        est = drv.step()
        assert est.status is Status.GOING_TO_CENTRE


def test_tracking_with_one_cluster_in_symmetric_room_keeps_tracking():
    pose = [2.5, 1.5, 0.4]
    loc = Localizer(FakeTracker(default=_result([pose], [1.0])), SquareJudge(), FakeStore(), PAPER)
    loc.set_pose(np.array(pose), np.eye(3) * 0.01)
    est = loc.update(OdometryReading(np.zeros(3)), np.array(pose))
    assert est.status is Status.TRACKING


def test_tracking_that_splits_into_rotated_clusters_becomes_ambiguous():
    pose = np.array([2.5, 1.5, 0.4])
    copies = rotated_copies(pose, CENTRE, SymmetryOrder.finite(4))
    tracker = FakeTracker(script=[_result(copies[:2], [0.6, 0.4])], default=_result([pose], [1]))
    loc = Localizer(tracker, SquareJudge(), FakeStore(), PAPER)
    loc.set_pose(pose, np.eye(3) * 0.01)
    est = loc.update(OdometryReading(np.zeros(3)), pose)
    assert est.status is Status.AMBIGUOUS
    assert est.order == SymmetryOrder.finite(4)
    assert est.request is not None
    assert est.request.kind is RequestKind.GO_TO_CENTRE


def test_tracking_that_loses_every_cluster_reports_lost():
    tracker = FakeTracker(script=[_result([[0, 0, 0]], [0.01])], default=_result([[0, 0, 0]], [1]))
    loc = Localizer(tracker, SquareJudge(symmetric=False), FakeStore(), PAPER)
    loc.set_pose(np.zeros(3), np.eye(3))
    est = loc.update(OdometryReading(np.zeros(3)), None)
    assert est.status is Status.LOST
    assert est.pose is None


def test_a_pose_lost_while_tracking_is_earned_again_only_after_n_converged_updates():
    good, weak = _result([[0.5, 0.5, 0.1]], [1.0]), _result([[0.5, 0.5, 0.1]], [0.01])
    tracker = FakeTracker(script=[good, good, good, weak], default=good)
    loc = Localizer(tracker, SquareJudge(symmetric=False), FakeStore(), PAPER)
    statuses = [loc.update(OdometryReading(np.zeros(3)), None).status for _ in range(7)]
    # earned at the 3rd, lost at the 4th, earned again only at the 3rd converged update after
    assert statuses == [Status.LOST] * 2 + [Status.TRACKING] + [Status.LOST] * 3 + [Status.TRACKING]


def test_collapsed_amcl_inside_known_symmetric_place_is_not_trusted():
    # The judge fails (near a wall) and AMCL collapsed to one copy: the map scorer says the
    # rotated copies explain the scan as well, so the pose is not earned.
    pose = np.array([3.3, 2.3, 0.4])
    loc = Localizer(
        FakeTracker(default=_result([pose], [1.0])),
        SquareJudge(symmetric=False),
        FakeStore(),
        PAPER,
        scorer=lambda poses, scan: np.ones(len(poses)),
        known_places=[PLACE],
    )
    est = loc.update(OdometryReading(np.zeros(3)), pose)
    assert est.status is Status.AMBIGUOUS
    target = compose(inverse(pose), np.array([*CENTRE, 0.0]))[:2]
    np.testing.assert_allclose(est.request.target, target)


def test_copies_that_do_not_fit_the_map_let_the_pose_be_earned():
    pose = np.array([3.3, 2.3, 0.4])
    loc = Localizer(
        FakeTracker(default=_result([pose], [1.0])),
        SquareJudge(symmetric=False),
        FakeStore(),
        PAPER,
        scorer=lambda poses, scan: np.r_[1.0, np.full(len(poses) - 1, 0.2)],
        known_places=[PLACE],
    )
    statuses = [loc.update(OdometryReading(np.zeros(3)), pose).status for _ in range(3)]
    assert statuses[-1] is Status.TRACKING


def test_reset_global_forgets_the_pose():
    tracker = FakeTracker(default=_result([[0.5, 0.5, 0.1]], [1.0], std=1.0))
    loc = Localizer(tracker, SquareJudge(symmetric=False), FakeStore(), PAPER)
    loc.set_pose(np.zeros(3), np.eye(3))
    loc.reset_global()
    assert tracker.globals_ == 1
    assert loc.phase == "lost"
    assert loc.update(OdometryReading(np.zeros(3)), None).status is Status.LOST


def test_settled_ambiguity_relocalizes_globally_when_leaving_the_place():
    true = np.array([1.2, 0.0, -1.0])
    judge = SquareJudge()
    store = FakeStore(places=[PLACE], decisions=[Decision("refused")] * 4)
    tracker = _ambiguous_tracker(true)
    loc = Localizer(tracker, judge, store, LocalizerConfig(decide_here=False, flip_patience=2))
    Driver(loc, true).run(400)
    assert loc.phase == "settled"
    judge.symmetric = False
    loc.update(OdometryReading(np.zeros(3)), None)
    est = loc.update(OdometryReading(np.zeros(3)), None)
    assert est.status is Status.LOST
    assert tracker.globals_ == 1


def test_estimate_invariants():
    with pytest.raises(ConfigurationError, match="tracking needs a pose"):
        Estimate(status=Status.TRACKING)
    with pytest.raises(ConfigurationError, match="only a tracking estimate carries a pose"):
        Estimate(status=Status.AMBIGUOUS, pose=np.zeros(3))


def test_request_validation():
    with pytest.raises(ConfigurationError, match="GO_TO_CENTRE needs"):
        Request(RequestKind.GO_TO_CENTRE)
    with pytest.raises(ConfigurationError, match="finite"):
        Request(RequestKind.GO_TO_CENTRE, target=np.array([np.nan, 0.0]))
    with pytest.raises(ConfigurationError, match="rotate needs a finite angle"):
        Request(RequestKind.ROTATE)


@pytest.mark.parametrize(
    ("field_", "value", "match"),
    [
        ("centre_tolerance", 0.0, "centre_tolerance"),
        ("min_cluster_weight", 1.5, "min_cluster_weight"),
        ("flip_patience", 0, "flip_patience"),
        ("converged_updates", 2.5, "converged_updates"),
    ],
)
def test_config_validation(field_, value, match):
    with pytest.raises(ConfigurationError, match=match):
        LocalizerConfig(**{field_: value})


def test_rotated_copies_takes_a_symmetry_order():
    with pytest.raises(ConfigurationError, match="SymmetryOrder"):
        rotated_copies(np.zeros(3), np.zeros(2), 4)  # type: ignore[arg-type]
    circle = rotated_copies(np.array([1.0, 0.0, 0.0]), np.zeros(2), SymmetryOrder.CIRCLE)
    assert circle.shape == (CIRCLE_SAMPLES, 3)


@settings(max_examples=40, deadline=None)
@given(
    x=st.floats(-3, 3),
    y=st.floats(-3, 3),
    th=st.floats(-3.1, 3.1),
    k=st.integers(2, 8),
)
def test_rotated_copies_are_recognised_as_symmetric(x, y, th, k):
    pose = np.array([x, y, th])
    centre = np.array([0.3, -0.2])
    copies = rotated_copies(pose, centre, SymmetryOrder.finite(k))
    hyps = [Hypothesis(p, 1.0 / k) for p in copies]
    kw = {"min_weight": 0.05, "position_tol": 0.05, "angle_tol": 0.05}
    assert symmetry_consistent(hyps, centre, SymmetryOrder.finite(k), **kw) == k
    # a cluster displaced far from the rotated copies is not counted (unless the displacement
    # happens to land it on another copy: x=-0.375, y=0, k=6 does)
    shifted = copies[1] + np.array([1.0, 1.0, 0.0])
    moved = [hyps[0], Hypothesis(shifted, 0.5)]
    clear = np.min(np.hypot(*(copies[:, :2] - shifted[:2]).T)) > 0.1
    if np.hypot(x - 0.3, y + 0.2) > 0.1 and clear:
        assert symmetry_consistent(moved, centre, SymmetryOrder.finite(k), **kw) == 1


class AxisSquareJudge(SquareJudge):
    """SquareJudge that also reports the axis (centre to the +x wall middle, base frame)."""

    def __call__(self, scan) -> SymmetryVerdict:
        v = super().__call__(scan)
        if not v.symmetric:
            return v
        mid = compose(inverse(scan), np.array([CENTRE[0] + HALF, CENTRE[1], 0.0]))[:2]
        d = mid - v.center
        return SymmetryVerdict(
            True,
            SymmetryOrder.finite(4),
            "polygon",
            v.center,
            v.gv_distance,
            facing=v.facing,
            axis=float(np.arctan2(d[1], d[0])),
        )


def test_candidates_from_scan_and_known_place_contain_the_true_pose():
    true = np.array([2.7, 0.3, 1.1])
    place = Place(3, CENTRE.copy(), heading0=0.0, m=4, order=4, gv_distance=HALF * math.sqrt(2))
    # AMCL knows nothing useful: one wide cluster somewhere else
    tracker = FakeTracker(default=_result([[0.0, 0.0, 0.0]], [1.0], std=2.0))
    loc = Localizer(tracker, AxisSquareJudge(), FakeStore(places=[place]), PAPER)
    est = loc.update(OdometryReading(np.zeros(3)), true)
    assert est.status is Status.AMBIGUOUS
    poses = np.array([h.pose for h in est.hypotheses])
    assert poses.shape == (4, 3)
    d = np.hypot(poses[:, 0] - true[0], poses[:, 1] - true[1])
    dth = np.abs(angle_diff(poses[:, 2], true[2]))
    assert np.min(d + dth) < 1e-9
    # the other three are the true pose rotated about the centre by multiples of 90 degrees
    expected = rotated_copies(true, CENTRE, SymmetryOrder.finite(4))
    for p in expected:
        assert np.min(np.hypot(poses[:, 0] - p[0], poses[:, 1] - p[1])) < 1e-9


def test_mapping_gives_the_store_the_measured_headings():
    true = np.array([2.5, 2.0, 0.7])
    store = FakeStore(places=[])
    loc = Localizer(
        _ambiguous_tracker(true),
        SquareJudge(),
        store,
        LocalizerConfig(decide_here=False, allow_mapping=True),
    )
    final = Driver(loc, true).run(600)
    assert len(store.added) == 1
    assert "new visual map" in final.reason
    headings = store.headings[0]
    assert headings is not None
    assert len(headings) == store.added[0][5]
    assert headings[0] == store.added[0][1]  # heading0 is the first image's heading


def test_decision_at_a_place_without_heading_reference_claims_no_pose():
    true = np.array([2.3, 1.2, 0.2])
    place = Place(9, CENTRE.copy(), 0.3, 4, 4, HALF * math.sqrt(2), heading_reliable=False)
    store = FakeStore(places=[place], decisions=[Decision("decided", 1, 0.0, 0.9)])
    tracker = _ambiguous_tracker(true)
    loc = Localizer(tracker, SquareJudge(), store, PAPER)
    final = Driver(loc, true).run(300)
    assert final.status is Status.AMBIGUOUS
    assert final.pose is None
    assert "no reliable heading reference" in final.reason
    assert tracker.seeded == []


def test_a_centre_decision_too_imprecise_to_claim_starts_the_claim_chain() -> None:
    """The camera chose the copy at the centre, but the laser cannot set the pose within the
    tolerance yet (a corridor's axis): AMCL is reseeded there and the claim chain starts at
    it, nothing is published now, and the pose is published once a scan confirms it."""
    import logging

    from symloc.grid.fields import surface_distance_field
    from symloc.localizer import deciding
    from symloc.localizer.centering import CentreFilter
    from symloc.localizer.claim import ClaimGate, Verdict
    from symloc.localizer.context import Context, Inputs, Record, Visit
    from symloc.localizer.notes import Notes
    from symloc.localizer.rules import Streak
    from symloc.localizer.types import Decision, DecisionStatus, TrackerResult
    from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
    from symloc.sim.rasterize import world_to_grid
    from symloc.sim.rooms import hallway

    room = hallway(20.0, 2.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    gate = ClaimGate(surface_distance_field(grid), (0.01, 0.01, 0.01, 0.01))
    centre = np.asarray(room.center, dtype=np.float64)
    truth = np.array([centre[0], centre[1], 0.0])
    near = RPLIDAR_A2.with_(range_max=6.0)  # the corridor's ends out of reach from its middle
    tracker = FakeTracker(default=_result([truth], [1.0]))
    notes = Notes(logging.getLogger("test"))
    ctx = Context(tracker, FakeStore(), LocalizerConfig(), gate, None, [], [], notes, Record())
    place = Place(1, centre, heading0=0.0, m=2, order=2, gv_distance=10.0)
    order = SymmetryOrder.finite(2)
    visit = Visit(order, 10.0, "rectangle", centre, CentreFilter(), place, Streak(3))
    decision = Decision(DecisionStatus.DECIDED, 0, 0.0, 0.9)
    scan = simulate_scan(room.world, truth, near, 0)
    result = TrackerResult(estimate=truth, covariance=np.eye(3) * 1e-4, hypotheses=())
    inp = Inputs(result, SquareJudge()(truth), scan, None, np.zeros(3))
    done = deciding.reseed(ctx, inp, visit, place, decision)
    assert done.outcome is deciding.Reseeded.WITHHELD
    assert done.estimate is not None
    assert done.estimate.status is Status.AMBIGUOUS  # nothing published now
    assert done.estimate.pose is None
    assert "published once a scan confirms it" in done.estimate.reason
    assert len(tracker.seeded) == 1  # AMCL reseeded at the decided pose
    assert gate.has_chain  # the claim chain starts there: the copy is chosen
    # driven 8.5 m along the corridor, its end near: the same chain is now confirmed
    moved = truth + np.array([8.5, 0.0, 0.0])
    claim = gate.check(np.array([8.5, 0.0, 0.0]), simulate_scan(room.world, moved, near, 1))
    assert claim.verdict is Verdict.CLAIM, claim.reason
    assert math.hypot(*(claim.pose[:2] - moved[:2])) < 0.1
