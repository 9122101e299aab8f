"""SE(2) pose graph over scan nodes and submaps, optimised with GTSAM.

Variables: one ``Pose2`` per scan node (key ``x<i>``) and per submap (key ``s<j>``), all in
the global (map) frame. Factors (``BetweenFactorPose2``):

- *intra-submap*: submap ``j`` to a node inserted into it, measured by the local front end;
- *odometry*: consecutive nodes, measured by the wheel odometry;
- *loop closure*: an older submap to a node, measured by scan matching, with a robust Huber
  loss so that a wrong closure cannot pull the whole graph (Hess et al. 2016, Section V).

The first node gets a tight prior. :meth:`PoseGraph.optimize` runs Levenberg-Marquardt.
"""

from __future__ import annotations

from dataclasses import dataclass

import gtsam
import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError

__all__ = ["PoseGraph", "PoseGraphParams"]

FloatArray = NDArray[np.float64]


def _sigmas(value: tuple[float, float, float], name: str) -> None:
    if len(value) != 3:
        raise ConfigurationError(f"{name}: expected 3 standard deviations (x, y, theta)")
    for k, v in enumerate(value):
        check_positive(v, f"{name}[{k}]")


@dataclass(frozen=True, slots=True)
class PoseGraphParams:
    """Noise of each factor type as standard deviations (x [m], y [m], theta [rad]).

    Parameters
    ----------
    intra_sigmas : tuple of 3 floats
        Node-in-submap constraints from the front end.
    loop_sigmas : tuple of 3 floats
        Loop-closure constraints (before the robust loss).
    odom_sigmas : tuple of 3 floats
        Base odometry noise; it grows with the motion by ``odom_scale`` per metre / radian.
    odom_scale : float
        Added standard deviation per unit of motion (fraction).
    huber_k : float
        Huber threshold in whitened units (standard deviations) on loop closures.
    max_iterations : int
        Levenberg-Marquardt iteration limit.
    """

    intra_sigmas: tuple[float, float, float] = (0.05, 0.05, 0.01)
    loop_sigmas: tuple[float, float, float] = (0.05, 0.05, 0.01)
    odom_sigmas: tuple[float, float, float] = (0.05, 0.05, 0.02)
    odom_scale: float = 0.2
    huber_k: float = 1.0
    max_iterations: int = 50

    def __post_init__(self) -> None:
        _sigmas(self.intra_sigmas, "PoseGraphParams.intra_sigmas")
        _sigmas(self.loop_sigmas, "PoseGraphParams.loop_sigmas")
        _sigmas(self.odom_sigmas, "PoseGraphParams.odom_sigmas")
        check_positive(self.odom_scale, "PoseGraphParams.odom_scale", allow_zero=True)
        check_positive(self.huber_k, "PoseGraphParams.huber_k")
        if int(self.max_iterations) != self.max_iterations or self.max_iterations < 1:
            raise ConfigurationError(
                f"PoseGraphParams.max_iterations: expected an integer >= 1, got"
                f" {self.max_iterations}"
            )


def _node(i: int) -> int:
    return int(gtsam.symbol("x", int(i)))


def _submap(j: int) -> int:
    return int(gtsam.symbol("s", int(j)))


def _pose2(p: ArrayLike) -> gtsam.Pose2:
    a = np.asarray(p, dtype=np.float64).reshape(3)
    return gtsam.Pose2(float(a[0]), float(a[1]), float(a[2]))


class PoseGraph:
    """Incrementally built pose graph; values are the current estimates."""

    def __init__(self, params: PoseGraphParams | None = None) -> None:
        self.params = params if params is not None else PoseGraphParams()
        self.graph = gtsam.NonlinearFactorGraph()
        self.values = gtsam.Values()
        self.loops: list[tuple[int, int]] = []
        self._intra = gtsam.noiseModel.Diagonal.Sigmas(np.array(self.params.intra_sigmas))
        base = gtsam.noiseModel.Diagonal.Sigmas(np.array(self.params.loop_sigmas))
        self._loop = gtsam.noiseModel.Robust.Create(
            gtsam.noiseModel.mEstimator.Huber.Create(self.params.huber_k), base
        )
        self.n_nodes = 0
        self.n_submaps = 0

    def add_node(self, i: int, initial: ArrayLike) -> None:
        """Add node ``i`` with an initial global pose (3,); the first node gets a prior."""
        self.values.insert(_node(i), _pose2(initial))
        if self.n_nodes == 0:
            prior = gtsam.noiseModel.Diagonal.Sigmas(np.array([1e-3, 1e-3, 1e-4]))
            self.graph.add(gtsam.PriorFactorPose2(_node(i), _pose2(initial), prior))
        self.n_nodes += 1

    def add_submap(self, j: int, initial: ArrayLike) -> None:
        """Add submap ``j`` with an initial global pose (3,)."""
        self.values.insert(_submap(j), _pose2(initial))
        self.n_submaps += 1

    def add_intra(self, j: int, i: int, node_in_submap: ArrayLike) -> None:
        """Constraint: node ``i`` sits at ``node_in_submap`` (3,) in submap ``j``."""
        self.graph.add(
            gtsam.BetweenFactorPose2(_submap(j), _node(i), _pose2(node_in_submap), self._intra)
        )

    def add_odometry(self, i: int, k: int, k_in_i: ArrayLike) -> None:
        """Constraint from odometry: node ``k`` at ``k_in_i`` (3,) in node ``i``'s frame."""
        d = np.asarray(k_in_i, dtype=np.float64)
        s = self.params.odom_scale
        trans = float(np.hypot(d[0], d[1]))
        sig = np.array(self.params.odom_sigmas) + s * np.array([trans, trans, abs(d[2])])
        noise = gtsam.noiseModel.Diagonal.Sigmas(sig)
        self.graph.add(gtsam.BetweenFactorPose2(_node(i), _node(k), _pose2(d), noise))

    def add_loop(self, j: int, i: int, node_in_submap: ArrayLike) -> None:
        """Loop closure: node ``i`` matched at ``node_in_submap`` (3,) in older submap ``j``."""
        self.graph.add(
            gtsam.BetweenFactorPose2(_submap(j), _node(i), _pose2(node_in_submap), self._loop)
        )
        self.loops.append((int(j), int(i)))

    def node_pose(self, i: int) -> FloatArray:
        """Current estimate of node ``i`` (3,)."""
        p = self.values.atPose2(_node(i))
        return np.array([p.x(), p.y(), p.theta()])

    def submap_pose(self, j: int) -> FloatArray:
        """Current estimate of submap ``j`` (3,)."""
        p = self.values.atPose2(_submap(j))
        return np.array([p.x(), p.y(), p.theta()])

    def node_poses(self) -> FloatArray:
        """``(n_nodes, 3)`` current node estimates in node order."""
        return np.array([self.node_pose(i) for i in range(self.n_nodes)]).reshape(-1, 3)

    def optimize(self) -> float:
        """Run Levenberg-Marquardt from the current values; returns the final error."""
        prm = gtsam.LevenbergMarquardtParams()
        prm.setMaxIterations(int(self.params.max_iterations))
        opt = gtsam.LevenbergMarquardtOptimizer(self.graph, self.values, prm)
        self.values = opt.optimize()
        return float(self.graph.error(self.values))
