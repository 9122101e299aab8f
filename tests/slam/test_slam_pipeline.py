"""End-to-end SLAM on a small synthetic room with a loop; pose graph; noisy odometry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import make_scan
from symloc.bench.slam_metrics import ate
from symloc.errors import ConfigurationError
from symloc.geometry import angle_diff, relative
from symloc.sim.odometry_noise import noisy_odometry
from symloc.slam import (
    LoopVerifierParams,
    PoseGraph,
    PoseGraphParams,
    SlamParams,
    SubmapParams,
    run_slam,
)


def _loop_path(n: int) -> np.ndarray:
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    x = 4.3 + 2.0 * np.cos(t)
    y = 3.0 + 1.1 * np.sin(t)
    th = t + math.pi / 2
    return np.column_stack([x, y, th])


def test_slam_closes_the_loop_and_beats_odometry(room: np.ndarray) -> None:
    truth = np.vstack([_loop_path(60), _loop_path(60)[:20]])
    rng = np.random.default_rng(3)
    scans = [make_scan(room, p, rng) for p in truth]
    odom = noisy_odometry(truth, (0.04, 0.01, 0.01, 0.04), rng=5)
    params = SlamParams(submap=SubmapParams(scans_per_submap=10), optimize_every=10)
    res = run_slam(scans, odom, params, progress=False)
    err_odom = ate(truth, odom).rmse
    err = ate(truth, res.poses).rmse
    assert err < 0.05
    assert err < err_odom / 3
    assert len(res.loop_closures) > 0
    assert res.n_submaps >= 5
    assert 20 < res.node_scans.size < len(scans)  # the motion filter dropped some scans
    # the map marks the room's walls occupied and its inside free
    g = res.grid
    wall = np.array([[4.0, 0.027]])  # bottom wall; the map frame is the first pose's world frame
    cell = g.world_to_cell(wall)[0]
    window = g.data[cell[0] - 3 : cell[0] + 4, cell[1] - 3 : cell[1] + 4]
    assert (window > 65).any()
    c = g.world_to_cell([[4.0, 3.0]])[0]
    assert 0 <= g.data[c[0], c[1]] < 20


def test_run_slam_validates_inputs(room: np.ndarray) -> None:
    scans = [make_scan(room, np.array([4.0, 3.0, 0.0]))]
    with pytest.raises(ConfigurationError, match="odometry: expected one pose per scan"):
        run_slam(scans, np.zeros((2, 3)), progress=False)
    with pytest.raises(ConfigurationError, match="min_score: expected a value in"):
        LoopVerifierParams(min_score=1.5)
    with pytest.raises(ConfigurationError, match="scans_per_submap: expected an integer >= 2"):
        SubmapParams(scans_per_submap=1)
    with pytest.raises(ConfigurationError, match=r"intra_sigmas\[2\]: expected a value > 0"):
        PoseGraphParams(intra_sigmas=(0.1, 0.1, 0.0))
    with pytest.raises(ConfigurationError, match="loop_resample_distance: expected a value >= 0"):
        SlamParams(loop_resample_distance=-1.0)
    with pytest.raises(
        ConfigurationError, match="loop_constrained_distance: expected a value >= 0"
    ):
        SlamParams(loop_constrained_distance=-0.5)


def test_loop_sampling_searches_less_and_still_closes_the_loop(room: np.ndarray) -> None:
    truth = np.vstack([_loop_path(60), _loop_path(60)[:20]])
    rng = np.random.default_rng(3)
    scans = [make_scan(room, p, rng) for p in truth]
    odom = noisy_odometry(truth, (0.04, 0.01, 0.01, 0.04), rng=5)
    base = {"submap": SubmapParams(scans_per_submap=10), "optimize_every": 10}
    every = run_slam(
        scans,
        odom,
        SlamParams(**base, loop_resample_distance=0.0, loop_constrained_distance=0.0),
        progress=False,
    )
    sampled = run_slam(
        scans,
        odom,
        SlamParams(**base, loop_resample_distance=1.0, loop_constrained_distance=3.0),
        progress=False,
    )
    assert 0 < len(sampled.loop_closures) < len(every.loop_closures)
    assert ate(truth, sampled.poses).rmse < 0.05


def _graph_with_a_wrong_loop(**kw: object) -> tuple[PoseGraph, np.ndarray]:
    # stiff odometry, so that a wrong loop cannot be absorbed by bending the chain
    g = PoseGraph(PoseGraphParams(odom_sigmas=(0.02, 0.02, 0.01), odom_scale=0.0, **kw))
    truth = _loop_path(12)
    for i, p in enumerate(truth):
        g.add_node(i, p)
        if i:
            g.add_odometry(i - 1, i, relative(truth[i - 1], truth[i]))
    g.add_submap(0, truth[0])
    g.add_intra(0, 0, np.zeros(3))
    g.add_loop(0, 11, relative(truth[0], truth[11]))
    g.add_loop(0, 6, relative(truth[0], truth[6]) + np.array([1.5, -1.0, 0.4]))  # wrong
    g.optimize()
    assert len(g.loops) == 2
    return g, truth


def test_pose_graph_robust_loss_limits_a_wrong_loop_and_check_removes_it() -> None:
    huber, truth = _graph_with_a_wrong_loop(robust="huber", huber_k=1.0)
    dcs, _ = _graph_with_a_wrong_loop(robust="dcs", dcs_phi=1.0)
    quadratic, _ = _graph_with_a_wrong_loop(robust="huber", huber_k=1e6)
    e_dcs = ate(truth, dcs.node_poses()).rmse
    e_huber = ate(truth, huber.node_poses()).rmse
    e_quad = ate(truth, quadratic.node_poses()).rmse
    assert e_huber < 0.5 * e_quad
    assert e_dcs < 0.2 * e_huber  # DCS all but ignores it
    for g in (huber, dcs):
        removed = g.check_loops()
        assert [(s, n) for s, n, _ in removed] == [(0, 6)]
        assert g.loops == [(0, 11)]
        assert ate(truth, g.node_poses()).rmse < 0.01


def test_noisy_odometry_is_seeded_and_starts_at_reference() -> None:
    truth = _loop_path(30)
    a = noisy_odometry(truth, rng=1)
    b = noisy_odometry(truth, rng=1)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(a[0], truth[0])
    assert not np.allclose(a, truth)
    exact = noisy_odometry(truth, (0, 0, 0, 0), rng=2)
    np.testing.assert_allclose(exact[:, :2], truth[:, :2], atol=1e-9)
    np.testing.assert_allclose(angle_diff(exact[:, 2], truth[:, 2]), 0.0, atol=1e-9)
    with pytest.raises(ConfigurationError, match=r"alphas\[1\]: expected a value >= 0"):
        noisy_odometry(truth, (0.1, -1, 0, 0))
