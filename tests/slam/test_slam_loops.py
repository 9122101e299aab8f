"""Loop closures that cannot break the map: verification, and an injected false closure."""

from __future__ import annotations

import math

import numpy as np

from conftest import make_scan
from symloc.bench.slam_metrics import ate
from symloc.geometry import compose, relative
from symloc.sim.odometry_noise import regime_odometry
from symloc.slam import (
    LoopCandidate,
    LoopVerifier,
    LoopVerifierParams,
    SlamParams,
    SubmapParams,
    run_slam,
)


def _cand(node: int, correction: tuple[float, float, float], **kw: float) -> LoopCandidate:
    args = {"score": 0.8, "runner_up": 0.5, "degenerate": False, "since_loop": 10.0}
    args.update(kw)
    return LoopCandidate(
        submap=1,
        node=node,
        measurement=np.zeros(3),
        covariance=np.eye(3) * 1e-4,
        score=float(args["score"]),
        runner_up=float(args["runner_up"]),
        degenerate=bool(args["degenerate"]),
        correction=np.array(correction),
        travel=100.0,
        since_loop=float(args["since_loop"]),
    )


def test_verifier_accepts_small_corrections_and_confirmed_large_ones() -> None:
    v = LoopVerifier(LoopVerifierParams(pending_nodes=10))
    assert v.submit(_cand(50, (0.05, -0.02, 0.01)), 50)  # within the drift gate
    assert not v.submit(_cand(51, (0.1, 0.0, 0.0), runner_up=0.78), 51)  # ambiguous
    assert not v.submit(_cand(52, (0.1, 0.0, 0.0), degenerate=True), 52)
    assert not v.submit(_cand(53, (0.1, 0.0, 0.0), score=0.3), 53)  # no match: not counted
    # a large correction after 10 m waits for a second candidate that asks for the same
    assert not v.submit(_cand(60, (1.5, 0.8, 0.2)), 60)
    got = v.submit(_cand(62, (1.45, 0.85, 0.21)), 62)
    assert sorted(c.node for c in got) == [60, 62]
    # a large correction nobody confirms is rejected once it is too old
    assert not v.submit(_cand(70, (-2.0, 1.0, -0.3)), 70)
    v.submit(_cand(90, (0.0, 0.0, 0.0)), 90)
    assert [(c.node, c.reason) for c in v.rejected] == [
        (51, "ambiguous"),
        (52, "degenerate"),
        (70, "inconsistent"),
    ]
    gt, gr = v.gate(100.0)
    assert gt > v.params.gate_trans
    assert gr > v.params.gate_rot


def _loop_path(n: int) -> np.ndarray:
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    return np.column_stack([4.3 + 2.0 * np.cos(t), 3.0 + 1.1 * np.sin(t), t + math.pi / 2])


def test_an_injected_false_loop_closure_is_rejected_and_the_map_holds(room: np.ndarray) -> None:
    truth = np.vstack([_loop_path(60), _loop_path(60)[:20]])
    rng = np.random.default_rng(3)
    scans = [make_scan(room, p, rng) for p in truth]
    odom = regime_odometry(truth, "realistic", 5)
    res = run_slam(
        scans,
        odom,
        SlamParams(submap=SubmapParams(scans_per_submap=10), optimize_every=10),
        progress=False,
    )
    graph = res.graph
    assert graph is not None
    before = ate(truth, res.poses).rmse
    assert before < 0.05
    loops_before = list(graph.loops)
    # a closure claiming the last node sits 1.2 m and 25 deg away from where it is
    last = graph.n_nodes - 1
    wrong = compose(relative(graph.submap_pose(0), graph.node_pose(last)), [1.2, -0.5, 0.45])
    graph.add_loop(0, last, wrong, np.diag([0.02**2, 0.02**2, 0.005**2]))
    graph.optimize()
    removed = graph.check_loops()
    assert (0, last) in [(s, n) for s, n, _ in removed]
    assert set(loops_before) <= set(graph.loops)  # the right ones survive
    node_poses = graph.node_poses()
    after = ate(truth[res.node_scans], node_poses).rmse
    assert after < 0.05
