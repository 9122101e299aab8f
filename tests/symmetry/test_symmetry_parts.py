from __future__ import annotations

import json
import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.scan import LaserScan
from symloc.sim.lidar import LDS01, PAPER_15M, RPLIDAR_A2, simulate_scan
from symloc.sim.rooms import build_room
from symloc.symmetry import (
    GVIndex,
    SymmetryConfig,
    SymmetryReport,
    algorithm1,
    fit_circle,
    judge_symmetry,
    rotational_order,
)
from symloc.symmetry.algorithm1 import count_groups
from symloc.symmetry.order import SymmetryOrder


# --- config ---------------------------------------------------------------------------------
def test_config_tolerance_follows_noise() -> None:
    cfg = SymmetryConfig(
        range_sigma=0.01, range_sigma_relative=0.02, k_sigma=4, model_tolerance=0.0
    )
    np.testing.assert_allclose(cfg.sigma([0.0, 1.0]), [0.01, math.hypot(0.01, 0.02)])
    np.testing.assert_allclose(cfg.point_tolerance([0.0]), [0.04])
    fixed = SymmetryConfig(tolerance=0.07)
    np.testing.assert_allclose(fixed.point_tolerance([1.0, 9.0]), [0.07, 0.07])
    assert SymmetryConfig.from_noise(0.02, 0.01).range_sigma_relative == 0.01


def test_config_from_lidar_presets() -> None:
    lds = SymmetryConfig.from_lidar(LDS01)
    assert lds.range_sigma == pytest.approx(0.005)
    assert lds.range_sigma_relative == pytest.approx(0.0175)
    paper = SymmetryConfig.from_lidar(PAPER_15M)
    assert paper.range_sigma == pytest.approx(0.01)
    assert paper.range_sigma_relative == 0.0
    rp = SymmetryConfig.from_lidar(RPLIDAR_A2)
    assert rp.range_sigma == pytest.approx(1e-3)
    assert rp.range_sigma_relative == pytest.approx(0.005)
    # the bound is never below the preset's own noise
    r = np.linspace(0.2, 15, 50)
    for preset, cfg in ((LDS01, lds), (PAPER_15M, paper), (RPLIDAR_A2, rp)):
        assert np.all(cfg.sigma(r) >= preset.sigma(r) - 1e-12)
    with pytest.raises(ConfigurationError, match="expected a LidarPreset"):
        SymmetryConfig.from_lidar(object())


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("range_sigma", 0.0, "range_sigma: expected a value > 0"),
        ("range_sigma_relative", 2.0, "range_sigma_relative: expected a value in"),
        ("k_sigma", -1.0, "k_sigma: expected a value > 0"),
        ("tolerance", 0.0, "tolerance: expected a value > 0"),
        ("model_tolerance", -0.1, "model_tolerance"),
        ("min_points", 2, "min_points: expected an integer >= 3"),
        ("min_points", 3.5, "min_points: expected an integer"),
        ("max_dropout_beams", -1, "max_dropout_beams"),
        ("max_blind_beams", 1, "max_blind_beams: expected >= max_dropout_beams"),
        ("min_line_points", True, "min_line_points: expected an integer"),
        ("max_polygon_sides", 2, "max_polygon_sides"),
        ("min_angle_tolerance", 1.0, "min_angle_tolerance"),
        ("max_door_width", 0.0, "max_door_width"),
    ],
)
def test_config_rejects_invalid_values(field: str, value: object, match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        SymmetryConfig(**{field: value})


# --- report ---------------------------------------------------------------------------------
def test_report_is_frozen_and_validates_kind() -> None:
    rep = SymmetryReport(
        "polygon", True, SymmetryOrder.finite(4), True, [0.0, 0.0], [[1, 1], [-1, 1]], 1.4, 0.0, "x"
    )
    assert rep.order == SymmetryOrder.finite(4)
    assert rep.to_dict()["order"] == 4
    assert not rep.continuous
    with pytest.raises(AttributeError):
        rep.kind = "circle"  # type: ignore[misc]
    with pytest.raises(ValueError, match=r"writable|read-only"):
        rep.center[0] = 1.0
    d = rep.to_dict()
    assert json.loads(json.dumps(d))["corners"] == [[1.0, 1.0], [-1.0, 1.0]]
    with pytest.raises(ConfigurationError, match="kind: expected one of"):
        SymmetryReport("blob", False, SymmetryOrder.finite(1), False, [0, 0], [], 0.0, 0.0, "")


# --- helpers --------------------------------------------------------------------------------
def test_fit_circle_and_rotational_order() -> None:
    ang = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    pts = np.column_stack([1 + 3 * np.cos(ang), -2 + 3 * np.sin(ang)])
    c, r = fit_circle(pts)
    np.testing.assert_allclose(c, [1, -2], atol=1e-9)
    assert r == pytest.approx(3.0)
    c, r = fit_circle(np.column_stack([np.arange(5.0), np.arange(5.0)]))
    assert math.isnan(r)
    sq = np.array([[1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0]])
    tol = np.full((4, 4), 1e-6)
    k, disp = rotational_order(sq, np.zeros(2), tol)
    assert k == 4
    assert np.all(disp < 1e-9)
    rect = sq * [2.0, 1.0]
    assert rotational_order(rect, np.zeros(2), tol)[0] == 2
    assert rotational_order(rect + np.array([0.3, 0.0]), np.zeros(2), tol)[0] == 1


def test_count_groups_is_circular() -> None:
    n, lab = count_groups(np.array([1, 1, 0, 0, 1, 0, 1, 1], dtype=bool))
    assert n == 2  # the run at the end joins the run at the start
    assert lab[0] == lab[-1]
    assert lab[0] != lab[4]
    assert lab[2] == -1
    assert count_groups(np.ones(4, bool))[0] == 1
    assert count_groups(np.zeros(4, bool))[0] == 0


# --- Algorithm 1 ----------------------------------------------------------------------------
def test_algorithm1_square_at_the_centre_and_off_centre() -> None:
    room = build_room("square", 3.0, lab=False)
    cfg = SymmetryConfig.from_lidar(PAPER_15M)
    at_centre = simulate_scan(room.world, np.array([0.0, 0.0, 0.3]), PAPER_15M, 1)
    res = algorithm1(at_centre, n=4, config=cfg)
    assert res.symmetric
    assert res.step == 16
    assert res.num_max == 4
    assert res.num_min == 4
    assert res.gv_distance == pytest.approx(3.0, abs=0.05)
    # off centre the mean of points is biased: the paper's test fails at step 7
    off = simulate_scan(room.world, np.array([1.2, 0.8, 0.3]), PAPER_15M, 1)
    res = algorithm1(off, n=4, config=cfg)
    assert not res.symmetric
    assert res.step == 7
    assert "num_max" in res.reason
    # wrong n fails
    assert not algorithm1(at_centre, n=3, config=cfg).symmetric


def test_algorithm1_circle_and_bad_input() -> None:
    scan = LaserScan(0.0, 2 * math.pi / 360, 0.1, 10.0, np.full(360, 2.0))
    res = algorithm1(scan)
    assert res.symmetric
    assert res.kind == "circle"
    few = scan.with_ranges(np.r_[np.full(5, 2.0), np.full(355, np.nan)])
    res = algorithm1(few)
    assert res.kind == "unknown"
    assert "too few points" in res.reason
    with pytest.raises(ConfigurationError, match="n: expected an integer >= 3"):
        algorithm1(scan, n=2)
    with pytest.raises(ConfigurationError, match="centroid: expected one of"):
        algorithm1(scan, centroid="x")


# --- G-V index ------------------------------------------------------------------------------
def test_gv_index_lookup_sorted_by_nearness() -> None:
    idx = GVIndex()
    idx.add("a", 3.0, kind="polygon", order=SymmetryOrder.finite(4), center=(1.0, 2.0))
    idx.add("b", 5.0)
    idx.add("c", 3.05, kind="circle", order=SymmetryOrder.CIRCLE)
    assert len(idx) == 3
    assert "a" in idx
    assert "z" not in idx
    np.testing.assert_allclose(idx.distances(), [3.0, 3.05, 5.0])
    hits = idx.lookup(3.04, tolerance=0.05)
    assert [h.place_id for h in hits] == ["c", "a"]
    assert idx.lookup(4.0, tolerance=0.5) == []
    assert [h.place_id for h in idx.lookup(5.0, tolerance=0.0)] == ["b"]
    assert hits[1].center == (1.0, 2.0)
    idx.remove("c")
    assert [e.place_id for e in idx] == ["a", "b"]


def test_gv_index_from_report_and_errors() -> None:
    room = build_room("pentagon", 4.0, lab=False)
    rep = judge_symmetry(simulate_scan(room.world, np.array([0.4, 0.1, 0.0]), PAPER_15M, 2))
    idx = GVIndex()
    e = idx.add_report("pentagon-4", rep)
    assert e.order == SymmetryOrder.finite(5)
    assert e.gv_distance == pytest.approx(4.0, abs=0.02)
    assert idx.lookup(4.0, tolerance=0.05)[0].place_id == "pentagon-4"
    with pytest.raises(ConfigurationError, match="already in the G-V index"):
        idx.add("pentagon-4", 2.0)
    with pytest.raises(ConfigurationError, match="gv_distance: expected a value > 0"):
        idx.add("x", -1.0)
    with pytest.raises(ConfigurationError, match="place_id: expected a non-empty string"):
        idx.add("", 1.0)
    with pytest.raises(ConfigurationError, match="not in the G-V index"):
        idx.remove("nope")
    with pytest.raises(ConfigurationError, match="tolerance: expected a value >= 0"):
        idx.lookup(1.0, tolerance=-1.0)
    with pytest.raises(ConfigurationError, match="gv_distance: expected a finite"):
        idx.lookup(math.nan, tolerance=1.0)
    bad = judge_symmetry(LaserScan(0.0, 0.1, 0.1, 5.0, np.full(10, np.nan)))
    with pytest.raises(ConfigurationError, match="expected a symmetric place"):
        idx.add_report("bad", bad)
