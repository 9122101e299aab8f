"""The confidence definition: hand-built results, scan consistency, hysteresis, rival search."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from mcl_fixtures import asymmetric_room, synthetic_scan

from symloc.errors import ConfigurationError
from symloc.geometry import compose
from symloc.grid import OccupancyGrid
from symloc.grid.fields import distance_field
from symloc.hypothesis import Hypothesis
from symloc.mcl import (
    Amcl,
    AmclParams,
    Confidence,
    ConfidenceConfig,
    ConfidenceJudge,
    RivalReport,
    ScanConsistency,
    assess,
    find_rival,
    scan_consistency,
)
from symloc.mcl.rival_search import match_scores, padded_field
from symloc.odometry import OdometryReading

TIGHT = np.diag([0.05**2, 0.05**2, math.radians(2.0) ** 2])
WIDE = np.diag([0.4**2, 0.4**2, math.radians(2.0) ** 2])
GOOD = ScanConsistency(0.97, 150, 0.4, True)
NO_RIVAL = ConfidenceConfig(rival_check=False)


def _result(shares=(1.0,), cov=TIGHT, estimate=(2.0, 3.0, 0.5), updated=True, skipped=False):
    est = np.asarray(estimate, dtype=float)
    hyps = [Hypothesis(est, w, covariance=cov, n_particles=100) for w in shares]
    return SimpleNamespace(
        estimate=est, covariance=cov, hypotheses=hyps, updated=updated, sensor_skipped=skipped
    )


def _chain(results, cons, config=NO_RIVAL, odoms=None):
    prev = None
    out = []
    for i, r in enumerate(results):
        c = cons[i] if isinstance(cons, list) else cons
        prev = assess(r, c, config, previous=prev, odom=None if odoms is None else odoms[i])
        out.append(prev)
    return out


# --------------------------------------------------------------------- config error paths
@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("min_weight_share", 0.5, r"min_weight_share: expected a value in \(0.5, 1\]"),
        ("min_weight_share", 1.2, "min_weight_share"),
        ("max_xy_std", 0.0, r"max_xy_std: expected a value > 0 m"),
        ("max_theta_std", math.pi, r"max_theta_std: expected a value in \(0, pi\)"),
        ("consistency_sigmas", -1.0, "consistency_sigmas"),
        ("min_scan_consistency", 0.0, r"min_scan_consistency: expected a value in \(0, 1\]"),
        ("min_beams", 0, "min_beams: expected an integer >= 1"),
        ("min_beams", 2.5, "min_beams: expected an integer"),
        ("hold_updates", 0, "hold_updates"),
        ("hold_updates", True, "hold_updates: expected an integer"),
        ("max_jump_xy", 0.0, "max_jump_xy"),
        ("max_jump_theta", 4.0, "max_jump_theta"),
        ("max_xy_std", float("nan"), "max_xy_std: expected a finite number"),
        ("max_xy_std", "0.1", "max_xy_std: expected a finite number"),
        ("rival_check", 1, "rival_check: expected a bool"),
        ("rival_margin", 1.0, r"rival_margin: expected a value in \[0, 1\)"),
        ("rival_tolerance_sigmas", 0.0, "rival_tolerance_sigmas"),
        ("rival_min_distance", -1.0, "rival_min_distance"),
        ("rival_min_angle", 0.0, "rival_min_angle"),
        ("evidence_updates", 0, "evidence_updates"),
        ("rival_recheck", 0, "rival_recheck"),
        ("rival_max_points", 5, "rival_max_points: expected an integer >= 10"),
    ],
)
def test_config_rejects_bad_values(field, value, match):
    with pytest.raises(ConfigurationError, match=match):
        ConfidenceConfig(**{field: value})


def test_config_is_frozen_and_defaults_are_documented_values():
    cfg = ConfidenceConfig()
    assert (cfg.min_weight_share, cfg.max_xy_std, cfg.hold_updates) == (0.9, 0.15, 3)
    assert cfg.max_theta_std == pytest.approx(math.radians(8.0))
    with pytest.raises(AttributeError):
        cfg.max_xy_std = 1.0  # type: ignore[misc]


def test_assess_rejects_bad_config_and_odom():
    with pytest.raises(ConfigurationError, match="config: expected a ConfidenceConfig"):
        assess(_result(), GOOD, config={"hold_updates": 1})  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="odom: expected finite shape"):
        assess(_result(), GOOD, NO_RIVAL, odom=[0.0, np.nan, 0.0])
    bad = _result(cov=np.full((3, 3), np.nan))
    with pytest.raises(ConfigurationError, match="covariance: expected a finite"):
        assess(bad, GOOD, NO_RIVAL)


# ------------------------------------------------------------------------ the checks
def test_dominant_tight_consistent_hypothesis_becomes_confident_after_hold():
    out = _chain([_result()] * 4, GOOD)
    assert [c.confident for c in out] == [False, False, True, True]
    assert [c.streak for c in out] == [1, 2, 3, 4]
    assert "1 of 3" in out[0].reason
    assert out[2].reason.startswith("confident")


def test_split_clusters_are_not_confident():
    out = _chain([_result(shares=(0.55, 0.45))] * 5, GOOD)
    assert not any(c.confident for c in out)
    assert "no dominant hypothesis" in out[-1].reason
    assert out[-1].weight_share == pytest.approx(0.55)


def test_wide_hypothesis_is_not_confident():
    out = _chain([_result(cov=WIDE)] * 5, GOOD)
    assert not any(c.confident for c in out)
    assert "too wide" in out[-1].reason
    assert out[-1].std_xy == pytest.approx(0.4)


@pytest.mark.parametrize(
    ("cons", "match"),
    [
        (ScanConsistency(0.6, 150, 0.4, True), "scan disagrees with the map"),
        (ScanConsistency(1.0, 4, 0.4, True), "too few valid beams"),
        (ScanConsistency(1.0, 150, 0.4, False), "not in a free cell"),
        (None, "not measured"),
    ],
)
def test_bad_scan_match_is_not_confident(cons, match):
    out = _chain([_result()] * 5, cons)
    assert not any(c.confident for c in out)
    assert match in out[-1].reason


def test_hysteresis_a_single_bad_update_restarts_the_count():
    cons = [GOOD, GOOD, GOOD, ScanConsistency(0.5, 150, 0.4, True), GOOD, GOOD, GOOD]
    out = _chain([_result()] * 7, cons)
    assert [c.confident for c in out] == [False, False, True, False, False, False, True]
    assert out[3].streak == 0


def test_calls_without_a_new_scan_keep_the_verdict():
    seq = [_result(), _result(), _result(), _result(updated=False), _result(skipped=True)]
    out = _chain(seq, [GOOD, GOOD, GOOD, None, None])
    assert out[3].confident
    assert out[4].confident
    assert out[4].streak == 3  # not advanced by calls that did not integrate a scan
    first = assess(_result(updated=False), None, NO_RIVAL)
    assert not first.confident
    assert "no scan integrated" in first.reason


def test_a_jump_against_the_odometry_restarts_the_count():
    odoms = [np.array([0.0, 0.0, 0.0]), np.array([0.5, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])]
    # The estimate follows the odometry (from (2, 3) heading 0), then hops 3 m sideways.
    ests = [(2.0, 3.0, 0.0), (2.5, 3.0, 0.0), (3.0, 6.0, 0.0)]
    out = _chain([_result(estimate=e) for e in ests], GOOD, odoms=odoms)
    assert out[1].streak == 2
    assert out[1].checks_pass
    assert not out[2].checks_pass
    assert "jumped" in out[2].reason
    consistent = _chain([_result(estimate=e) for e in ests[:2]], GOOD, odoms=odoms[:2])
    assert consistent[1].streak == 2


def test_rival_check_gates_confidence():
    cfg = ConfidenceConfig(rival_recheck=2, rival_grace=0)  # one failed update is a doubt
    prev = None
    for _ in range(2):
        prev = assess(_result(), GOOD, cfg, previous=prev)
    assert not prev.locally_confident
    c3 = assess(_result(), GOOD, cfg, previous=prev)
    assert c3.locally_confident
    assert c3.rival_due
    assert not c3.confident
    assert c3.checks_pass
    assert c3.streak == 3
    # the caller runs the search and assesses the same update again with its report
    amb = RivalReport(True, 0.98, 0.97, np.array([9.0, 9.0, 0.0]), 10, 80)
    c3 = assess(_result(), GOOD, cfg, previous=prev, rival=amb)
    assert not c3.confident
    assert "ambiguous place" in c3.reason
    assert "9.00" in c3.reason
    c4 = assess(_result(), GOOD, cfg, previous=c3)
    assert not c4.rival_due
    assert not c4.confident
    c5 = assess(_result(), GOOD, cfg, previous=c4)
    assert c5.rival_due
    uniq = RivalReport(False, 0.98, 0.5, None, 3, 80)
    c5 = assess(_result(), GOOD, cfg, previous=c4, rival=uniq)
    assert c5.confident
    assert c5.unique
    assert "unique" in c5.reason
    c6 = assess(_result(), GOOD, cfg, previous=c5)
    assert c6.confident
    assert c6.rival_searches == 2
    assert not c6.rival_due
    c7 = assess(_result(), ScanConsistency(0.1, 150, 0.4, True), cfg, previous=c6)
    c8 = assess(_result(), GOOD, cfg, previous=c7)
    assert not c7.unique
    assert not c7.locally_confident
    assert not c8.unique


def _prove(cfg: ConfidenceConfig) -> Confidence:
    """Three passing updates, the third with a search that found no rival: a place proven
    unique."""
    prev = None
    for _ in range(2):
        prev = assess(_result(), GOOD, cfg, previous=prev)
    uniq = RivalReport(False, 0.98, 0.5, None, 3, 80)
    c = assess(_result(), GOOD, cfg, previous=prev, rival=uniq)
    assert c.confident
    assert c.unique
    assert c.proven == 0
    return c


BAD_SCAN = ScanConsistency(0.1, 150, 0.4, True)


def test_place_proven_unique_is_followed_through_a_short_doubt():
    # a person walks past: rival_grace failed updates, the estimate still moves as the odometry
    # says: no new search, confident again once the hysteresis is rebuilt
    cfg = ConfidenceConfig(rival_grace=2)
    c = _prove(cfg)
    for _ in range(2):
        c = assess(_result(), BAD_SCAN, cfg, previous=c)
        assert not c.confident
        assert c.unique
    track = c.track
    for k in range(3):
        c = assess(_result(), GOOD, cfg, previous=c)
        assert not c.rival_due
        assert c.confident == (k == 2)
    assert c.track == track
    assert c.rival_searches == 0  # none in this streak: the proof was carried


def test_a_longer_doubt_needs_a_new_proof():
    cfg = ConfidenceConfig(rival_grace=2)
    c = _prove(cfg)
    for _ in range(3):
        c = assess(_result(), BAD_SCAN, cfg, previous=c)
    assert not c.unique
    assert c.track == 1
    for _ in range(3):
        c = assess(_result(), GOOD, cfg, previous=c)
    assert c.rival_due
    assert not c.confident


def test_a_new_cluster_or_a_jump_needs_a_new_proof():
    cfg = ConfidenceConfig(rival_grace=5)
    c = _prove(cfg)
    split = assess(_result(shares=(0.6, 0.4)), GOOD, cfg, previous=c)
    assert not split.unique
    assert split.track == c.track + 1
    # a jump: the estimate 2 m from where the odometry moved it
    c = _prove(cfg)
    c = dataclasses.replace(c, odom=np.zeros(3))
    jumped = assess(_result(estimate=(2.0, 0.0, 0.0)), BAD_SCAN, cfg, previous=c, odom=np.zeros(3))
    assert not jumped.unique
    assert jumped.track == c.track + 1


def test_a_followed_place_is_searched_again_every_period():
    cfg = ConfidenceConfig(rival_period=4)
    c = _prove(cfg)
    for _ in range(3):
        c = assess(_result(), GOOD, cfg, previous=c)
        assert c.confident
        assert not c.rival_due
    c = assess(_result(), GOOD, cfg, previous=c)
    assert c.confident  # still confident while the search runs
    assert c.rival_due
    amb = RivalReport(True, 0.98, 0.97, np.array([9.0, 9.0, 0.0]), 10, 80)
    prev = c
    c = assess(_result(), GOOD, cfg, previous=prev, rival=amb)
    assert not c.confident
    assert not c.unique


@settings(max_examples=40, deadline=None)
@given(
    share=st.floats(0.5, 1.0),
    sxy=st.floats(0.0, 0.5),
    frac=st.floats(0.0, 1.0),
    n=st.integers(1, 6),
)
def test_confident_only_if_every_threshold_holds(share, sxy, frac, n):
    cov = np.diag([sxy**2, (sxy / 2) ** 2, math.radians(3) ** 2])
    cons = ScanConsistency(frac, 100, 0.4, True)
    out = _chain([_result(shares=(share,), cov=cov)] * n, cons)
    cfg = NO_RIVAL
    expected = (
        share >= cfg.min_weight_share
        and sxy <= cfg.max_xy_std
        and frac >= cfg.min_scan_consistency
        and n >= cfg.hold_updates
    )
    assert out[-1].confident == expected


# ------------------------------------------------------------------ scan consistency
def test_scan_consistency_true_pose_vs_wrong_pose():
    grid = asymmetric_room()
    field = distance_field(grid, 2.0)
    rng = np.random.default_rng(1)
    pose = np.array([5.0, 3.0, 0.3])
    scan = synthetic_scan(grid, pose, rng)
    good = scan_consistency(field, pose, scan, sigma_hit=0.2)
    assert good.fraction > 0.97
    assert good.pose_free
    assert good.n_beams > 100
    assert good.tolerance == pytest.approx(0.4)
    assert good.points.shape == (good.n_beams, 2)
    bad = scan_consistency(field, [2.0, 4.5, 2.0], scan, sigma_hit=0.2)
    assert bad.fraction < 0.8
    inside = scan_consistency(field, [2.5, 2.0, 0.0], scan, sigma_hit=0.2)  # in the obstacle
    assert not inside.pose_free


def test_scan_consistency_errors():
    grid = asymmetric_room()
    field = distance_field(grid, 2.0)
    scan = synthetic_scan(grid, np.array([5.0, 3.0, 0.0]), np.random.default_rng(0))
    with pytest.raises(ConfigurationError, match="pose: expected finite shape"):
        scan_consistency(field, [1.0, 2.0], scan)
    with pytest.raises(ConfigurationError, match="sigma_hit: expected a value > 0"):
        scan_consistency(field, [5.0, 3.0, 0.0], scan, sigma_hit=0.0)
    with pytest.raises(ConfigurationError, match="laser_likelihood_max_dist"):
        scan_consistency(field, [5.0, 3.0, 0.0], scan, sigma_hit=0.5, sigmas=5.0)
    empty = scan.with_ranges(np.full(len(scan), np.inf))
    none = scan_consistency(field, [5.0, 3.0, 0.0], empty)
    assert none.n_beams == 0
    assert none.fraction == 0.0


# ---------------------------------------------------------------------- rival search
def _square_room() -> OccupancyGrid:
    d = np.zeros((100, 100), np.int8)
    d[0, :] = d[-1, :] = d[:, 0] = d[:, -1] = 100
    return OccupancyGrid(d, 0.05)


def test_rival_search_finds_the_symmetric_copy_in_a_square_room():
    grid = _square_room()  # walls on the map's edge: searched through a padded field
    field = distance_field(grid, 2.0)
    pose = np.array([1.5, 1.0, 0.4])
    scan = synthetic_scan(grid, pose, np.random.default_rng(2), n=90)
    pts = scan_consistency(field, pose, scan).points
    big = padded_field(grid, 2.0)
    assert big.grid.free_mask.sum() == grid.free_mask.sum()
    rep = find_rival(big, pts, pose, tol=0.2)
    assert rep.ambiguous
    assert rep.estimate_score > 0.95
    # the rival is one of the 3 other images under 90-degree rotations about the centre
    c = np.array([2.5, 2.5])
    imgs = []
    for k in (1, 2, 3):
        a = k * np.pi / 2
        rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        imgs.append(c + rot @ (pose[:2] - c))
    assert min(np.hypot(*(rep.rival_pose[:2] - i)) for i in imgs) < 0.2


def test_rival_search_finds_none_in_an_asymmetric_room():
    grid = asymmetric_room()
    field = distance_field(grid, 2.0)
    pose = np.array([5.0, 3.0, 0.3])
    scan = synthetic_scan(grid, pose, np.random.default_rng(3))
    pts = scan_consistency(field, pose, scan).points
    rep = find_rival(field, pts, pose, tol=0.2)
    assert not rep.ambiguous
    assert rep.estimate_score > 0.95
    assert rep.rival_score < rep.estimate_score - 0.05
    assert rep.n_points == 80


def test_match_scores_and_rival_errors():
    grid = asymmetric_room()
    field = distance_field(grid, 2.0)
    assert match_scores(field, np.zeros((2, 3)), np.zeros((0, 2)), 0.1).tolist() == [0.0, 0.0]
    with pytest.raises(ConfigurationError, match="tol: expected a finite value > 0"):
        find_rival(field, np.ones((5, 2)), np.zeros(3), tol=0.0)
    with pytest.raises(ConfigurationError, match=r"margin: expected a value in \[0, 1\)"):
        find_rival(field, np.ones((5, 2)), np.zeros(3), tol=0.2, margin=1.0)
    with pytest.raises(ConfigurationError, match="estimate: expected finite shape"):
        find_rival(field, np.ones((5, 2)), np.zeros(2), tol=0.2)
    nothing = find_rival(field, np.zeros((0, 2)), np.array([5.0, 3.0, 0.0]), tol=0.2)
    assert nothing.ambiguous
    assert nothing.n_points == 0


# ------------------------------------------------------------------------- on the filter
def _amcl(grid: OccupancyGrid) -> Amcl:
    a = 0.002
    params = AmclParams(
        max_particles=800,
        min_particles=200,
        laser_model_type="likelihood_field_prob",
        alpha1=a,
        alpha2=a,
        alpha3=a,
        alpha4=a,
    )
    return Amcl(grid, params, rng=5)


def test_the_judge_follows_the_filter_and_resets_with_it():
    grid = asymmetric_room()
    rng = np.random.default_rng(4)
    amcl = _amcl(grid)
    judge = ConfidenceJudge(amcl)
    assert judge.verdict is None
    true = np.array([5.0, 3.0, 0.3])
    amcl.initialize_pose(true, np.diag([0.01, 0.01, 0.001]))
    odom = np.array([1.0, 1.0, 0.0])
    conf = None
    for i in range(6):
        step = np.array([0.3, 0.0, 0.0]) if i % 2 == 0 else np.array([0.0, 0.0, 0.3])
        res, conf = judge.update(OdometryReading(odom), synthetic_scan(grid, true, rng))
        true, odom = compose(true, step), compose(odom, step)
    assert conf is not None
    assert conf is judge.verdict
    assert conf.confident, conf.reason
    assert res.estimate.shape == (3,)
    assert res.n_hypotheses == 1
    assert judge.n_rival_searches == 1
    # a new initialisation of the filter starts a new judgement, as a reset would
    amcl.initialize_global()
    assert judge.verdict is None
    assert judge.n_rival_searches == 1  # counted over the judge's life


def test_the_filter_update_judges_nothing():
    grid = asymmetric_room()
    rng = np.random.default_rng(4)
    amcl = _amcl(grid)
    amcl.initialize_pose([5.0, 3.0, 0.3], np.diag([0.01, 0.01, 0.001]))
    res = amcl.update(OdometryReading([1.0, 1.0, 0.0]), synthetic_scan(grid, [5.0, 3.0, 0.3], rng))
    assert not hasattr(res, "confidence")
    assert not hasattr(amcl, "confidence")
    assert amcl.counters.n_initializations == 1


def test_the_judge_rejects_a_bad_config():
    with pytest.raises(ConfigurationError, match="config: expected a ConfidenceConfig"):
        ConfidenceJudge(Amcl(asymmetric_room()), {"hold_updates": 2})  # type: ignore[arg-type]
