from __future__ import annotations

import numpy as np
import pytest
from mcl_fixtures import asymmetric_room, synthetic_scan

from symloc.errors import ConfigurationError, DataFormatError
from symloc.geometry import angle_diff, compose
from symloc.grid import OccupancyGrid
from symloc.mcl import Amcl, AmclParams, NotInitializedError
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan


def _drive(grid, amcl, true, steps, rng, *, step=(0.3, 0.0, 0.25)):
    """Drive a seeded path that stays in free space; feed odometry + scans to the filter."""
    odom = np.array([3.0, -1.0, 0.4])  # arbitrary odom frame
    res = None
    df_free = grid.free_mask
    for _ in range(steps):
        res = amcl.update(OdometryReading(odom), synthetic_scan(grid, true, rng))
        move = np.array(step)
        nxt = compose(true, move)
        ahead = compose(true, [0.6, 0.0, 0.0])
        cell = grid.world_to_cell(ahead[None, :2])
        if not (grid.in_bounds(cell)[0] and df_free[cell[0, 0], cell[0, 1]]):
            move = np.array([0.0, 0.0, 0.9])
            nxt = compose(true, move)
        true = nxt
        noisy = move + rng.normal(0, [0.01, 0.01, 0.01])
        odom = compose(odom, noisy)
    res = amcl.update(OdometryReading(odom), synthetic_scan(grid, true, rng))
    return res, true


def test_converges_in_asymmetric_room_from_uniform_start():
    grid = asymmetric_room()
    rng = np.random.default_rng(5)
    params = AmclParams(
        max_particles=4000, min_particles=300, laser_model_type="likelihood_field_prob"
    )
    amcl = Amcl(grid, params, rng=7)
    amcl.initialize_global()
    assert len(amcl.particles) == 4000
    res, true = _drive(grid, amcl, np.array([5.0, 3.0, 0.3]), 30, rng)
    err = np.hypot(*(res.estimate[:2] - true[:2]))
    assert err < 0.3, (res.estimate, true)
    assert abs(angle_diff(res.estimate[2], true[2])) < np.deg2rad(10)
    assert res.n_hypotheses == 1
    assert res.weight > 0.9
    assert np.sqrt(res.covariance[0, 0]) < 0.3
    assert len(res.particles) < 4000  # KLD shrank the converged set
    assert res.weights.sum() == pytest.approx(1.0)
    assert np.all(np.isfinite(res.particles))


def test_tracking_from_initial_pose_default_model():
    grid = asymmetric_room()
    rng = np.random.default_rng(2)
    amcl = Amcl(grid, AmclParams(max_particles=1000, min_particles=200), rng=3)
    true = np.array([2.0, 4.0, -0.2])
    amcl.initialize_pose(true + np.array([0.2, -0.1, 0.05]))
    res, true = _drive(grid, amcl, true, 15, rng)
    # nav2's defaults (alphas 0.2, 1 + sum pz^3) keep a wide cloud: ~0.2 m is typical
    assert np.hypot(*(res.estimate[:2] - true[:2])) < 0.35
    assert abs(angle_diff(res.estimate[2], true[2])) < np.deg2rad(10)


@pytest.mark.parametrize("model", ["beam", "likelihood_field_prob"])
def test_other_sensor_models_track(model):
    grid = asymmetric_room()
    rng = np.random.default_rng(4)
    p = AmclParams(
        max_particles=400, min_particles=100, laser_model_type=model, do_beamskip=(model != "beam")
    )
    amcl = Amcl(grid, p, rng=4)
    true = np.array([2.0, 4.0, -0.2])
    amcl.initialize_pose(true, np.diag([0.04, 0.04, 0.01]))
    res, true = _drive(grid, amcl, true, 6, rng)
    assert np.hypot(*(res.estimate[:2] - true[:2])) < 0.25


def test_update_gating_and_resample_interval():
    grid = asymmetric_room()
    rng = np.random.default_rng(0)
    amcl = Amcl(grid, AmclParams(max_particles=300, min_particles=300, resample_interval=2), rng=0)
    true = np.array([2.0, 4.0, 0.0])
    amcl.initialize_pose(true)
    scan = synthetic_scan(grid, true, rng)
    r0 = amcl.update(OdometryReading([0, 0, 0]), scan)
    assert r0.updated
    assert not r0.resampled
    r1 = amcl.update(OdometryReading([0.1, 0, 0.1]), scan)
    assert not r1.updated  # below update_min_d = 0.25 and update_min_a = 0.2
    np.testing.assert_array_equal(r1.particles, r0.particles)
    r2 = amcl.update(OdometryReading([0.3, 0, 0]), scan)
    assert r2.updated
    assert r2.resampled
    r3 = amcl.update(OdometryReading([0.3, 0, 0.25]), scan)
    assert r3.updated
    assert not r3.resampled
    assert amcl.counters.n_updates == 3
    assert amcl.counters.n_resamples == 1


def test_scan_without_valid_beams_is_a_counted_skip():
    grid = asymmetric_room()
    amcl = Amcl(grid, AmclParams(max_particles=200, min_particles=200), rng=0)
    amcl.initialize_pose([2.0, 4.0, 0.0])
    empty = LaserScan(-np.pi / 2, 0.1, 0.1, 10.0, np.array([np.inf, np.nan, 0.01, 50.0]))
    r = amcl.update(OdometryReading([0, 0, 0]), empty)
    assert r.sensor_skipped
    assert r.updated
    assert not r.resampled
    assert amcl.n_scans_skipped == 1
    assert np.all(np.isfinite(r.estimate))
    assert np.all(np.isfinite(r.covariance))
    r = amcl.update(OdometryReading([1.0, 0, 0]), empty)
    assert amcl.n_scans_skipped == 2
    assert np.all(np.isfinite(r.estimate))


def test_recovery_injects_after_kidnapping():
    grid = asymmetric_room()
    rng = np.random.default_rng(8)
    p = AmclParams(
        max_particles=500, min_particles=500, recovery_alpha_slow=0.001, recovery_alpha_fast=0.1
    )
    amcl = Amcl(grid, p, rng=8)
    true = np.array([2.0, 4.0, -0.2])
    amcl.initialize_pose(true, np.diag([0.01, 0.01, 0.005]))
    _drive(grid, amcl, true, 5, rng)
    kidnapped = np.array([6.5, 1.5, 2.0])
    _drive(grid, amcl, kidnapped, 5, rng)
    assert amcl.counters.n_injected > 0


def test_no_free_cells_raises():
    grid = OccupancyGrid(np.full((10, 10), 100, np.int8), 0.1)
    with pytest.raises(ConfigurationError, match="no free cell"):
        Amcl(grid, AmclParams(), rng=0)
    unknown = OccupancyGrid(np.full((10, 10), -1, np.int8), 0.1)
    with pytest.raises(ConfigurationError, match="no free cell"):
        Amcl(unknown)


def test_bad_inputs_raise():
    grid = asymmetric_room()
    amcl = Amcl(grid, AmclParams(max_particles=100, min_particles=100), rng=0)
    scan = LaserScan(0.0, 0.1, 0.1, 10.0, np.ones(5))
    with pytest.raises(NotInitializedError, match="initialize_global"):
        amcl.update(OdometryReading([0, 0, 0]), scan)
    with pytest.raises(NotInitializedError, match="initialize"):
        _ = amcl.particles
    with pytest.raises(DataFormatError, match="finite"):
        OdometryReading([np.nan, 0, 0])
    amcl.initialize_global()
    with pytest.raises(DataFormatError, match="OdometryReading"):
        amcl.update(np.zeros(3), scan)  # type: ignore[arg-type]
    with pytest.raises(DataFormatError, match="LaserScan"):
        amcl.update(OdometryReading([0, 0, 0]), np.ones(5))  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="laser_pose"):
        amcl.update(OdometryReading([0, 0, 0]), scan, laser_pose=(0, np.nan, 0))
    with pytest.raises(ConfigurationError, match="covariance"):
        amcl.initialize_pose([1, 1, 0], -np.eye(3))
    with pytest.raises(ConfigurationError, match="covariance"):
        amcl.initialize_pose([1, 1, 0], np.array([[1, 2, 0], [0, 1, 0], [0, 0, 1.0]]))
    with pytest.raises(ConfigurationError, match="pose"):
        amcl.initialize_pose([1, np.inf, 0])
    with pytest.raises(ConfigurationError, match="OccupancyGrid"):
        Amcl(np.zeros((4, 4)))  # type: ignore[arg-type]


def test_initialize_pose_samples_the_covariance():
    amcl = Amcl(asymmetric_room(), AmclParams(max_particles=20000, min_particles=100), rng=1)
    cov = np.array([[0.04, 0.01, 0.0], [0.01, 0.09, 0.0], [0.0, 0.0, 0.01]])
    amcl.initialize_pose([3.0, 2.0, np.pi - 0.05], cov)
    p = amcl.particles
    assert np.all(p[:, 2] <= np.pi)
    assert np.all(p[:, 2] > -np.pi)
    np.testing.assert_allclose(np.cov(p[:, :2].T), cov[:2, :2], atol=0.005)
    st = amcl.cluster_stats()
    assert st.weights[0] > 0.95  # one cluster across the +-pi seam


def test_global_init_is_uniform_over_free_cells():
    grid = asymmetric_room()
    amcl = Amcl(grid, AmclParams(max_particles=20000, min_particles=100), rng=2)
    amcl.initialize_global()
    cells = grid.world_to_cell(amcl.particles[:, :2])
    assert np.all(grid.free_mask[cells[:, 0], cells[:, 1]])
    left = np.mean(amcl.particles[:, 0] < 4.0)
    assert left == pytest.approx(np.mean(np.nonzero(grid.free_mask)[1] < 80), abs=0.02)
    assert abs(np.mean(np.cos(amcl.particles[:, 2]))) < 0.03


def test_likelihood_exponent_tempers_the_weights():
    grid = asymmetric_room()
    scan = synthetic_scan(grid, np.array([2.0, 4.0, 0.0]), np.random.default_rng(0))
    ess = []
    for expo in (1.0, 0.05):
        p = AmclParams(
            max_particles=2000,
            min_particles=2000,
            resample_interval=5,
            laser_model_type="likelihood_field_prob",
            laser_likelihood_exponent=expo,
        )
        amcl = Amcl(grid, p, rng=1)
        amcl.initialize_global()
        r = amcl.update(OdometryReading([0, 0, 0]), scan)
        assert not r.resampled
        ess.append(1.0 / np.sum(r.weights**2))
    assert ess[1] > 3 * ess[0]
    with pytest.raises(ConfigurationError, match="laser_likelihood_exponent"):
        AmclParams(laser_likelihood_exponent=0.0)
