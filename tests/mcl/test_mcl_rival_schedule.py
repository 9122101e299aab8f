"""The rival search spread over scans (bounded cost per update) and scheduled by the judge."""

from __future__ import annotations

import numpy as np
import pytest
from mcl_fixtures import asymmetric_room, synthetic_scan, twin_rooms

from symloc.errors import ConfigurationError
from symloc.geometry import compose
from symloc.grid import OccupancyGrid
from symloc.mcl import Amcl, AmclParams, ConfidenceConfig, ConfidenceJudge, find_rival
from symloc.mcl import rival_search as rs
from symloc.mcl.confidence import scan_consistency
from symloc.mcl.rival_schedule import RivalSearchRun
from symloc.odometry import OdometryReading


def _square_room() -> OccupancyGrid:
    d = np.zeros((100, 100), np.int8)
    d[0, :] = d[-1, :] = d[:, 0] = d[:, -1] = 100
    return OccupancyGrid(d, 0.05)


def _images(pose: np.ndarray, centre: np.ndarray) -> list[np.ndarray]:
    """The 3 other positions of ``pose`` under 90-degree rotations about ``centre``."""
    out = []
    for k in (1, 2, 3):
        a = k * np.pi / 2
        rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        out.append(centre + rot @ (pose[:2] - centre))
    return out


def _evidence(grid: OccupancyGrid, pose: np.ndarray, seed: int) -> np.ndarray:
    scan = synthetic_scan(grid, pose, np.random.default_rng(seed), n=90)
    pts = scan_consistency(rs.padded_field(grid, 2.0), pose, scan).points
    assert pts is not None
    return pts


def test_a_search_spread_over_calls_reports_what_one_call_does() -> None:
    grid = _square_room()
    field = rs.padded_field(grid, 2.0)
    pose = np.array([1.5, 1.0, 0.4])
    pts = _evidence(grid, pose, 2)
    whole = find_rival(field, pts, pose, tol=0.2)
    budget = 20_000
    run = RivalSearchRun(
        rs.rival_search_steps(field, pts, pose, tol=0.2, chunk_pairs=budget), track=3
    )
    report = None
    while report is None:
        report = run.advance(budget)
    assert run.calls > 3  # the work was spread
    assert run.advance(budget) is report  # an ended run keeps its report
    assert report.ambiguous == whole.ambiguous
    assert report.estimate_score == whole.estimate_score
    assert report.rival_score == whole.rival_score
    assert report.n_candidates == whole.n_candidates
    np.testing.assert_array_equal(report.rival_pose, whole.rival_pose)
    assert report.ambiguous
    assert min(np.hypot(*(report.rival_pose[:2] - i)) for i in _images(pose, np.full(2, 2.5))) < 0.2
    with pytest.raises(ConfigurationError, match="budget: expected an integer >= 1"):
        run.advance(0)
    with pytest.raises(ConfigurationError, match="chunk_pairs: expected an integer >= 1"):
        next(rs.rival_search_steps(field, pts, pose, tol=0.2, chunk_pairs=0))


def test_positions_left_out_before_the_lattice_change_no_report(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # two identical rooms side by side, and an asymmetric one: with and without the
    # heading-free test of the positions, the same reports
    cases = [(twin_rooms(), np.array([1.5, 1.5, 0.3]))]
    cases.append((asymmetric_room(), np.array([5.0, 3.0, 0.3])))
    for grid, est in cases:
        field = rs.padded_field(grid, 2.0)
        pts = _evidence(grid, est, 5)
        left_out = rs._may_reach(
            field, rs.coarse_lattice(field.grid, 6), np.full(pts.shape[0], 0.5), 0.9
        )
        fast = find_rival(field, pts, est, tol=0.1)
        with monkeypatch.context() as mp:
            mp.setattr(rs, "_may_reach", lambda f, xy, reach, at_least: np.ones(len(xy), bool))
            slow = find_rival(field, pts, est, tol=0.1)
        assert not left_out.all()  # short reaches leave positions out
        assert fast.ambiguous == slow.ambiguous
        assert fast.estimate_score == slow.estimate_score
        assert fast.rival_score == slow.rival_score
        assert fast.n_candidates == slow.n_candidates
        if slow.rival_pose is None:
            assert fast.rival_pose is None
        else:
            np.testing.assert_array_equal(fast.rival_pose, slow.rival_pose)


def _amcl(grid: OccupancyGrid) -> Amcl:
    a = 0.002
    params = AmclParams(
        max_particles=600,
        min_particles=200,
        laser_model_type="likelihood_field_prob",
        alpha1=a,
        alpha2=a,
        alpha3=a,
        alpha4=a,
    )
    return Amcl(grid, params, rng=5)


def test_the_scheduled_search_finds_the_rival_in_a_square_room_also_after_a_kidnap() -> None:
    grid = _square_room()
    rng = np.random.default_rng(4)
    amcl = _amcl(grid)
    # a budget far below one search: each search takes several updates
    judge = ConfidenceJudge(amcl, ConfidenceConfig(rival_budget=300_000))
    true = np.array([1.5, 1.0, 0.4])
    odom = np.array([0.0, 0.0, 0.0])
    amcl.initialize_pose(true, np.diag([0.01, 0.01, 0.001]))
    spans = []
    reports = []
    for i in range(40):
        if i == 20:  # kidnapped: carried to another place, the filter put there anew
            true = np.array([3.2, 3.6, -2.0])
            amcl.initialize_pose(true, np.diag([0.01, 0.01, 0.001]))
        step = np.array([0.0, 0.0, 0.3])  # turning on the spot
        running = judge.search
        n = judge.n_rival_searches
        _, conf = judge.update(OdometryReading(odom), synthetic_scan(grid, true, rng))
        assert not conf.confident, (i, conf.reason)  # a square room never earns a pose
        if judge.n_rival_searches > n:
            assert conf.rival is not None
            spans.append(1 if running is None else running.calls)
            reports.append((i, conf.rival))
        true, odom = compose(true, step), compose(odom, step)
    assert reports, "no search ended"
    assert max(spans) > 1  # spread over updates
    before = [r for i, r in reports if i < 20]
    after = [r for i, r in reports if i >= 20]
    assert before
    assert after
    assert all(r.ambiguous for _, r in reports)
    assert judge.n_rival_searches == len(reports)


def test_a_place_proven_unique_is_not_searched_again_while_followed() -> None:
    grid = asymmetric_room()
    rng = np.random.default_rng(4)
    amcl = _amcl(grid)
    judge = ConfidenceJudge(amcl)
    true = np.array([5.0, 3.0, 0.3])
    amcl.initialize_pose(true, np.diag([0.01, 0.01, 0.001]))
    odom = np.array([1.0, 1.0, 0.0])
    confident = []
    for i in range(24):
        step = np.array([0.3, 0.0, 0.0]) if i % 2 == 0 else np.array([0.0, 0.0, 0.3])
        scan = synthetic_scan(grid, true, rng)
        if i in (10, 11):  # someone in front of the laser: half the beams short
            r = np.array(scan.ranges)
            r[::2] = np.minimum(r[::2], 0.4)
            scan = type(scan)(
                scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max, r
            )
        _, conf = judge.update(OdometryReading(odom), scan)
        confident.append(conf.confident)
        true, odom = compose(true, step), compose(odom, step)
        if not (0.8 < true[0] < 7.2 and 0.8 < true[1] < 5.2):
            break
    assert judge.n_rival_searches == 1, judge.n_rival_searches
    assert confident[-1]


def _offices(n: int = 3) -> OccupancyGrid:
    """``n x n`` identical 3 m offices with a box each: many places look alike."""
    side = 60
    d = np.full((n * side + 2, n * side + 2), 100, np.int8)
    for i in range(n):
        for j in range(n):
            r0, c0 = 1 + i * side, 1 + j * side
            d[r0 + 1 : r0 + side - 1, c0 + 1 : c0 + side - 1] = 0
            d[r0 + 10 : r0 + 18, c0 + 35 : c0 + 50] = 100
    return OccupancyGrid(d, 0.05)


def test_a_search_stops_once_too_many_places_look_alike() -> None:
    grid = _offices()
    field = rs.padded_field(grid, 2.0)
    est = np.array([1.2, 1.0, 0.2])
    pts = _evidence(grid, est, 6)
    full = find_rival(field, pts, est, tol=0.1, max_candidates=10**9)
    early = find_rival(field, pts, est, tol=0.1, max_candidates=300)
    assert full.ambiguous  # 8 other offices
    assert early.ambiguous  # the same verdict ...
    assert 300 < early.n_candidates < full.n_candidates  # ... from part of the lattice
    # its rival is the best-bounded candidate: a bound at least the threshold
    assert early.rival_pose is not None
    assert early.rival_score >= early.estimate_score - 0.1
    far = np.hypot(*(early.rival_pose[:2] - est[:2])) > 0.7
    turned = abs(np.angle(np.exp(1j * (early.rival_pose[2] - est[2])))) > np.radians(24.0)
    assert far or turned  # beyond the lattice-relaxed distance or angle of a rival


def _all_steps(
    field: rs.DistanceField, pts: np.ndarray, est: np.ndarray, **kw: float
) -> tuple[list[int], rs.RivalReport]:
    """The pairs every slice of a search yields, and its report."""
    steps = rs.rival_search_steps(field, pts, est, tol=0.1, chunk_pairs=30_000, **kw)
    yields = []
    while True:
        try:
            yields.append(next(steps))
        except StopIteration as done:
            return yields, done.value


def test_the_heading_groups_above_the_lattice_change_no_report_and_score_fewer_poses(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # two identical rooms (a rival), an asymmetric room (unique) and nine offices cut short
    # by max_candidates (the early exit counts the same candidates): with and without the
    # level above the lattice, the same slices and the same reports
    cases: list[tuple[OccupancyGrid, np.ndarray, dict[str, float]]] = [
        (twin_rooms(), np.array([1.5, 1.5, 0.3]), {}),
        (asymmetric_room(), np.array([5.0, 3.0, 0.3]), {}),
        (_offices(), np.array([1.2, 1.0, 0.2]), {"max_candidates": 300}),
    ]
    scored = {"poses": 0}
    plain_scores = rs._Scorer.scores

    def counting(self: rs._Scorer, local: np.ndarray, at_least: float | None = None) -> np.ndarray:
        scored["poses"] += local.shape[0]
        return plain_scores(self, local, at_least)

    monkeypatch.setattr(rs._Scorer, "scores", counting)
    ambiguous = []
    for grid, est, kw in cases:
        field = rs.padded_field(grid, 2.0)
        pts = _evidence(grid, est, 5)
        scored["poses"] = 0
        grouped = _all_steps(field, pts, est, **kw)
        with_groups = scored["poses"]
        with monkeypatch.context() as mp:
            mp.setattr(rs, "_GROUP", 1)
            scored["poses"] = 0
            plain = _all_steps(field, pts, est, **kw)
            without = scored["poses"]
        assert grouped[0] == plain[0]  # the same slices: a budget spreads it the same way
        a, b = grouped[1], plain[1]
        assert (a.ambiguous, a.estimate_score, a.rival_score) == (
            b.ambiguous,
            b.estimate_score,
            b.rival_score,
        )
        assert (a.n_candidates, a.n_points) == (b.n_candidates, b.n_points)
        if b.rival_pose is None:
            assert a.rival_pose is None
        else:
            np.testing.assert_array_equal(a.rival_pose, b.rival_pose)
        assert with_groups < without  # the level above the lattice left poses out
        ambiguous.append(a.ambiguous)
    assert ambiguous == [True, False, True]


def test_the_heading_groups_cover_the_lattice() -> None:
    heads = -np.pi + (np.arange(7) + 0.5) * (2 * np.pi / 7)
    groups = rs._heading_groups(heads, 3)
    starts = [i for i, g in enumerate(groups) if g is not None]
    assert starts == [0, 3, 6]
    for i in starts:
        centre, spread = groups[i]  # type: ignore[misc]
        members = heads[i : i + 3]
        assert np.max(np.abs(members - centre)) == pytest.approx(spread)
    assert groups[6] == (heads[6], 0.0)  # a last group of one
