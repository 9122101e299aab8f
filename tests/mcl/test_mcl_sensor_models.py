from __future__ import annotations

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.grid.fields import distance_field
from symloc.mcl.beam_model import beam_model_weights, raycast_grid
from symloc.mcl.beams import select_beams
from symloc.mcl.likelihood_field import likelihood_field_weights
from symloc.mcl.likelihood_field_prob import likelihood_field_prob_log_weights
from symloc.scan import LaserScan

RES = 0.1


def _wall_grid():
    """4 m x 2 m grid, a wall (one cell thick) at column 30 (x in [3.0, 3.1))."""
    d = np.zeros((20, 40), np.int8)
    d[:, 30] = 100
    return OccupancyGrid(d, RES)


def _scan(ranges, angle_min=0.0, inc=0.1, rmax=10.0, rmin=0.05):
    return LaserScan(angle_min, inc, rmin, rmax, np.asarray(ranges, dtype=float))


def _pz(d, z_hit=0.5, z_rand=0.5, sigma=0.2, rmax=10.0):
    return z_hit * np.exp(-(d * d) / (2 * sigma * sigma)) + z_rand / rmax


def test_select_beams_follows_nav2():
    r = np.arange(1.0, 181.0) / 20.0 + 0.1
    r[3] = np.nan
    r[6] = 0.01  # below range_min -> max range
    r[9] = np.inf
    b = select_beams(_scan(r, inc=np.deg2rad(1.0)), 60)
    # step (180 - 1) // 59 = 3 -> beams 0, 3, ..., 177
    assert b.n_steps == 60
    assert b.n_invalid == 1
    assert b.ranges.size == 59
    assert b.n_no_return == 2
    assert not b.hit[1]
    assert not b.hit[2]
    assert b.ranges[1] == 10.0
    assert b.ranges[0] == pytest.approx(0.15)
    b2 = select_beams(_scan(r, inc=np.deg2rad(1.0)), 60, laser_max_range=5.0)
    assert b2.range_max == 5.0
    assert b2.n_no_return > b.n_no_return
    with pytest.raises(ConfigurationError, match="max_beams"):
        select_beams(_scan(r, inc=0.01), 1)
    with pytest.raises(ConfigurationError, match="LaserScan"):
        select_beams(r, 60)  # type: ignore[arg-type]


def test_likelihood_field_hand_computed():
    g = _wall_grid()
    df = distance_field(g, 2.0)
    # robot at cell (10, 10) centre (1.05, 1.05) looking +x; beam ends 1.5 m ahead at x=2.55:
    # the end cell is column 25 (centre 2.55), 5 cells from the wall column -> d = 0.5 m
    scan = _scan([1.5, np.inf], inc=np.pi / 2)
    b = select_beams(scan, 60)
    parts = np.array([[1.05, 1.05, 0.0], [1.05, 1.05, np.pi], [-50.0, 0.0, 0.0]])
    w = likelihood_field_weights(df, parts, b, z_hit=0.5, z_rand=0.5, sigma_hit=0.2)
    # second particle: end point x = -0.45 -> off the map -> max_dist 2.0; third: off the map
    expected = 1.0 + np.array([_pz(0.5) ** 3, _pz(2.0) ** 3, _pz(2.0) ** 3])
    np.testing.assert_allclose(w, expected, rtol=1e-5)


def test_likelihood_field_laser_pose_offset():
    df = distance_field(_wall_grid(), 2.0)
    b = select_beams(_scan([1.0, np.inf], inc=np.pi / 2), 60)
    # laser 0.5 m ahead of the base: end point at 1.05 + 0.5 + 1.0 = 2.55 -> d = 0.5
    w = likelihood_field_weights(
        df,
        np.array([[1.05, 1.05, 0.0]]),
        b,
        z_hit=0.5,
        z_rand=0.5,
        sigma_hit=0.2,
        laser_pose=np.array([0.5, 0.0, 0.0]),
    )
    assert w[0] == pytest.approx(1.0 + _pz(0.5) ** 3, rel=1e-5)


def test_no_return_beams_are_ignored():
    df = distance_field(_wall_grid(), 2.0)
    b = select_beams(_scan([np.inf, 20.0]), 60)
    w = likelihood_field_weights(df, np.zeros((4, 3)), b, z_hit=0.5, z_rand=0.5, sigma_hit=0.2)
    np.testing.assert_array_equal(w, 1.0)


def test_likelihood_field_prob_hand_computed_and_beamskip():
    df = distance_field(_wall_grid(), 2.0)
    # two beams: one hits the wall for every particle, one ends in open space for all
    b = select_beams(_scan([1.95, 0.5], angle_min=0.0, inc=np.pi / 2), 60)
    parts = np.tile([1.05, 1.05, 0.0], (10, 1))
    logs, rep = likelihood_field_prob_log_weights(
        df, parts, b, z_hit=0.5, z_rand=0.5, sigma_hit=0.2
    )
    # beam 1 ends at (3.0, 1.05): cell column 30 = wall -> d = 0; beam 2 ends at (1.05, 1.55)
    # cell (15, 10): 20 cells from the wall -> d = 2.0 (clipped)
    assert logs[0] == pytest.approx(np.log(_pz(0.0)) + np.log(_pz(2.0)), rel=1e-5)
    assert rep.n_skipped == 0
    logs2, rep2 = likelihood_field_prob_log_weights(
        df,
        parts,
        b,
        z_hit=0.5,
        z_rand=0.5,
        sigma_hit=0.2,
        do_beamskip=True,
        beam_skip_distance=0.5,
        beam_skip_threshold=0.3,
        beam_skip_error_threshold=0.9,
    )
    # beam 2 is near no obstacle for any particle -> skipped
    assert rep2.n_skipped == 1
    assert not rep2.fell_back
    assert logs2[0] == pytest.approx(np.log(_pz(0.0)), rel=1e-5)
    # if nearly all beams would be skipped, all are used
    b3 = select_beams(_scan([0.5, 0.6], inc=np.pi / 2), 60)
    logs3, rep3 = likelihood_field_prob_log_weights(
        df,
        parts,
        b3,
        z_hit=0.5,
        z_rand=0.5,
        sigma_hit=0.2,
        do_beamskip=True,
        beam_skip_error_threshold=0.9,
    )
    assert rep3.fell_back
    assert rep3.n_skipped == 2
    assert logs3[0] == pytest.approx(2 * np.log(_pz(2.0)), rel=1e-5)


def test_raycast_grid_distances():
    g = _wall_grid()
    r = raycast_grid(
        g,
        np.array([[1.05, 1.05], [1.05, 1.05], [1.05, 1.05]]),
        np.array([0.0, np.pi, np.pi / 2]),
        10.0,
    )
    # to the wall face at x = 3.0: 1.95 m (within a cell); to the left map edge: 1.05 m
    assert r[0] == pytest.approx(1.95, abs=RES)
    assert r[1] == pytest.approx(1.05, abs=RES)
    assert r[2] == pytest.approx(0.95, abs=RES)
    capped = raycast_grid(g, np.array([[1.05, 1.05]]), np.array([0.0]), 1.0)
    assert capped[0] == 1.0


def test_beam_model_hand_computed():
    g = _wall_grid()
    params = {
        "z_hit": 0.5,
        "z_short": 0.05,
        "z_max": 0.05,
        "z_rand": 0.5,
        "sigma_hit": 0.2,
        "lambda_short": 0.1,
    }
    parts = np.array([[1.05, 1.05, 0.0]])
    expected_range = raycast_grid(g, parts[:, :2], np.array([0.0]), 10.0)[0]
    for obs in (expected_range, expected_range - 0.5, expected_range + 0.3):
        b = select_beams(_scan([obs, np.inf], inc=np.pi / 2), 60)
        w = beam_model_weights(g, parts, b, **params)
        z = obs - expected_range
        pz1 = 0.5 * np.exp(-z * z / (2 * 0.04)) + 0.5 / 10.0
        if z < 0:
            pz1 += 0.05 * 0.1 * np.exp(-0.1 * obs)
        # the no-return beam (pi/2) expects 0.95 m: z = 10 - 0.95
        r2 = raycast_grid(g, parts[:, :2], np.array([np.pi / 2]), 10.0)[0]
        z2 = 10.0 - r2
        pz2 = 0.5 * np.exp(-z2 * z2 / 0.08) + 0.05
        assert w[0] == pytest.approx(1.0 + pz1**3 + pz2**3, rel=1e-9)


def test_blocked_evaluation_matches_small_batches():
    df = distance_field(_wall_grid(), 2.0)
    rng = np.random.default_rng(0)
    ranges = rng.uniform(0.2, 3.0, 60)
    b = select_beams(LaserScan(-np.pi, 2 * np.pi / 60, 0.05, 10.0, ranges), 60)
    parts = np.column_stack(
        [rng.uniform(-1, 5, 3000), rng.uniform(-1, 3, 3000), rng.uniform(-np.pi, np.pi, 3000)]
    )
    kw = {"z_hit": 0.5, "z_rand": 0.5, "sigma_hit": 0.2}
    big = likelihood_field_weights(df, parts, b, **kw)
    small = np.concatenate(
        [likelihood_field_weights(df, parts[i : i + 7], b, **kw) for i in range(0, 3000, 7)]
    )
    np.testing.assert_allclose(big, small, rtol=1e-6)
    big_l, _ = likelihood_field_prob_log_weights(df, parts, b, **kw)
    small_l = np.concatenate(
        [
            likelihood_field_prob_log_weights(df, parts[i : i + 7], b, **kw)[0]
            for i in range(0, 3000, 7)
        ]
    )
    np.testing.assert_allclose(big_l, small_l, rtol=1e-6)
