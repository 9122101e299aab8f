"""SE(2) pose graph over scan nodes and submaps, optimised with GTSAM.

Variables: one ``Pose2`` per scan node (key ``x<i>``) and per submap (key ``s<j>``), all in
the global (map) frame. Factors (``BetweenFactorPose2``):

- *intra-submap*: submap ``j`` to a node inserted into it, measured by the local front end;
- *odometry*: consecutive nodes, measured by the wheel odometry;
- *loop closure*: an older submap to a node, measured by scan matching, with a robust loss
  (Dynamic Covariance Scaling, Agarwal et al. 2013, by default; Huber as in Hess et al. 2016
  on request) so that a wrong closure cannot pull the whole graph.

Each factor takes its own covariance (the front end's match covariance, which is huge along
directions a scan does not constrain; the odometry's learnt noise), or the fixed sigmas of
:class:`PoseGraphParams`. After an optimisation, :meth:`PoseGraph.check_loops` removes the loop
closures whose Mahalanobis residual stays above ``loop_chi2`` (a closure the rest of the
graph disagrees with) and reports them.

The first node gets a tight prior. :meth:`PoseGraph.optimize` runs Levenberg-Marquardt.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gtsam
import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import relative, wrap_angle

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
        Huber threshold in whitened units (standard deviations) on loop closures (with
        ``robust="huber"``).
    robust : str
        Loss on loop closures: ``"dcs"`` (Dynamic Covariance Scaling with ``dcs_phi``) or
        ``"huber"``.
    dcs_phi : float
        DCS parameter (squared whitened units; a closure starts losing weight beyond
        ``sqrt(phi)`` standard deviations; Agarwal et al. use 1 with looser covariances).
    loop_chi2 : float
        A loop whose squared Mahalanobis residual exceeds this after an optimisation is
        removed (default: the 99.9 % quantile of chi-square with 3 degrees of freedom).
    loop_check_sigmas : tuple of 3 floats
        Added (as variances) to a loop's covariance for that check: the error a correct
        closure may keep in a graph whose submaps are not perfect.
    max_iterations : int
        Levenberg-Marquardt iteration limit.
    """

    intra_sigmas: tuple[float, float, float] = (0.05, 0.05, 0.01)
    loop_sigmas: tuple[float, float, float] = (0.05, 0.05, 0.01)
    odom_sigmas: tuple[float, float, float] = (0.05, 0.05, 0.02)
    odom_scale: float = 0.2
    huber_k: float = 1.0
    robust: str = "huber"
    dcs_phi: float = 9.0
    loop_chi2: float = 16.27
    loop_check_sigmas: tuple[float, float, float] = (0.1, 0.1, math.radians(1.0))
    max_iterations: int = 50

    def __post_init__(self) -> None:
        _sigmas(self.intra_sigmas, "PoseGraphParams.intra_sigmas")
        _sigmas(self.loop_sigmas, "PoseGraphParams.loop_sigmas")
        _sigmas(self.odom_sigmas, "PoseGraphParams.odom_sigmas")
        _sigmas(self.loop_check_sigmas, "PoseGraphParams.loop_check_sigmas")
        check_positive(self.odom_scale, "PoseGraphParams.odom_scale", allow_zero=True)
        check_positive(self.huber_k, "PoseGraphParams.huber_k")
        check_positive(self.dcs_phi, "PoseGraphParams.dcs_phi")
        check_positive(self.loop_chi2, "PoseGraphParams.loop_chi2")
        if self.robust not in ("dcs", "huber"):
            raise ConfigurationError(
                f"PoseGraphParams.robust: expected 'dcs' or 'huber', got {self.robust!r}"
            )
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


def _gaussian(covariance: ArrayLike) -> gtsam.noiseModel.Base:
    c = np.asarray(covariance, dtype=np.float64).reshape(3, 3)
    return gtsam.noiseModel.Gaussian.Covariance(0.5 * (c + c.T))


@dataclass(frozen=True, slots=True)
class _Loop:
    submap: int
    node: int
    measurement: FloatArray
    information: FloatArray
    factor: int


class PoseGraph:
    """Incrementally built pose graph; values are the current estimates."""

    def __init__(self, params: PoseGraphParams | None = None) -> None:
        self.params = params if params is not None else PoseGraphParams()
        self.graph = gtsam.NonlinearFactorGraph()
        self.values = gtsam.Values()
        self._loops: list[_Loop] = []
        self.removed_loops: list[tuple[int, int, float]] = []
        self._intra = gtsam.noiseModel.Diagonal.Sigmas(np.array(self.params.intra_sigmas))
        self._loop_base = np.diag(np.array(self.params.loop_sigmas) ** 2)
        self.n_nodes = 0
        self.n_submaps = 0
        # map prior index -> the same prior with its covariance for node_information, or None
        self._map_priors: dict[int, gtsam.PriorFactorPose2 | None] = {}

    @property
    def loops(self) -> list[tuple[int, int]]:
        """``(submap, node)`` of the loop closures in the graph."""
        return [(lp.submap, lp.node) for lp in self._loops]

    def _robust(self, base: gtsam.noiseModel.Base) -> gtsam.noiseModel.Base:
        est: gtsam.noiseModel.mEstimator.Base
        if self.params.robust == "huber":
            est = gtsam.noiseModel.mEstimator.Huber.Create(self.params.huber_k)
        else:
            est = gtsam.noiseModel.mEstimator.DCS.Create(self.params.dcs_phi)
        return gtsam.noiseModel.Robust.Create(est, base)

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

    def add_intra(
        self, j: int, i: int, node_in_submap: ArrayLike, covariance: ArrayLike | None = None
    ) -> None:
        """Constraint: node ``i`` sits at ``node_in_submap`` (3,) in submap ``j``.

        ``covariance`` (3, 3) defaults to ``intra_sigmas``.
        """
        noise = self._intra if covariance is None else _gaussian(covariance)
        self.graph.add(
            gtsam.BetweenFactorPose2(_submap(j), _node(i), _pose2(node_in_submap), noise)
        )

    def add_odometry(
        self, i: int, k: int, k_in_i: ArrayLike, covariance: ArrayLike | None = None
    ) -> None:
        """Constraint from odometry: node ``k`` at ``k_in_i`` (3,) in node ``i``'s frame.

        ``covariance`` (3, 3) defaults to ``odom_sigmas`` grown by ``odom_scale`` per unit
        of motion.
        """
        d = np.asarray(k_in_i, dtype=np.float64)
        noise: gtsam.noiseModel.Base
        if covariance is None:
            s = self.params.odom_scale
            trans = float(np.hypot(d[0], d[1]))
            sig = np.array(self.params.odom_sigmas) + s * np.array([trans, trans, abs(d[2])])
            noise = gtsam.noiseModel.Diagonal.Sigmas(sig)
        else:
            noise = _gaussian(covariance)
        self.graph.add(gtsam.BetweenFactorPose2(_node(i), _node(k), _pose2(d), noise))

    def add_loop(
        self, j: int, i: int, node_in_submap: ArrayLike, covariance: ArrayLike | None = None
    ) -> None:
        """Loop closure: node ``i`` matched at ``node_in_submap`` (3,) in older submap ``j``.

        ``covariance`` (3, 3) defaults to ``loop_sigmas``; the robust loss is on top.
        """
        cov = self._loop_base if covariance is None else np.asarray(covariance, dtype=np.float64)
        z = np.asarray(node_in_submap, dtype=np.float64).reshape(3).copy()
        self.graph.add(
            gtsam.BetweenFactorPose2(_submap(j), _node(i), _pose2(z), self._robust(_gaussian(cov)))
        )
        check = 0.5 * (cov + cov.T) + np.diag(np.array(self.params.loop_check_sigmas) ** 2)
        self._loops.append(_Loop(int(j), int(i), z, np.linalg.inv(check), self.graph.size() - 1))

    def add_map_prior(
        self,
        i: int,
        pose: ArrayLike,
        covariance: ArrayLike,
        *,
        marginal_covariance: ArrayLike | None = None,
    ) -> int:
        """Node ``i`` matched at ``pose`` (3,) in the global map (the final refinement's
        scan-to-map match), with ``covariance`` (3, 3) in the node's frame and a Huber loss;
        returns the factor's index (for :meth:`remove_factors`). ``marginal_covariance``
        (3, 3) replaces ``covariance`` in :meth:`node_information` (None: the prior is left
        out there)."""
        noise = gtsam.noiseModel.Robust.Create(
            gtsam.noiseModel.mEstimator.Huber.Create(self.params.huber_k), _gaussian(covariance)
        )
        self.graph.add(gtsam.PriorFactorPose2(_node(i), _pose2(pose), noise))
        index = int(self.graph.size() - 1)
        self._map_priors[index] = (
            None
            if marginal_covariance is None
            else gtsam.PriorFactorPose2(_node(i), _pose2(pose), _gaussian(marginal_covariance))
        )
        return index

    def remove_factors(self, indices: list[int]) -> None:
        """Remove the factors at ``indices`` (from :meth:`add_map_prior`)."""
        for k in indices:
            self.graph.remove(int(k))
            self._map_priors.pop(int(k), None)

    def loop_chi2(self) -> FloatArray:
        """Squared Mahalanobis residual ``(L,)`` of every loop closure at the current values
        (with ``loop_check_sigmas`` added to its covariance)."""
        out = np.zeros(len(self._loops))
        for k, lp in enumerate(self._loops):
            est = relative(self.submap_pose(lp.submap), self.node_pose(lp.node))
            e = relative(lp.measurement, est)
            e[2] = float(wrap_angle(e[2]))
            out[k] = float(e @ lp.information @ e)
        return out

    def check_loops(self, *, rounds: int = 8, share: float = 0.25) -> list[tuple[int, int, float]]:
        """Remove, worst first, the loops the optimised graph disagrees with.

        Each round removes the loops whose residual exceeds ``loop_chi2`` (at most ``share``
        of the loops, the worst ones) and optimises again, until none exceeds it or after
        ``rounds`` rounds: a wrong closure pulls the graph towards itself, so the residuals of
        the right ones only show once it is gone. Call after :meth:`optimize`; returns the
        removed loops ``(submap, node, chi2)``.
        """
        removed: list[tuple[int, int, float]] = []
        for _ in range(rounds):
            chi2 = self.loop_chi2()
            bad = np.flatnonzero(chi2 > self.params.loop_chi2)
            if bad.size == 0:
                break
            worst = bad[np.argsort(chi2[bad])[::-1]]
            worst = worst[: max(1, int(share * len(self._loops)))]
            for k in sorted(worst.tolist(), reverse=True):
                lp = self._loops.pop(k)
                self.graph.remove(lp.factor)
                removed.append((lp.submap, lp.node, float(chi2[k])))
            self.optimize()
        self.removed_loops.extend(removed)
        return removed

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

    def node_information(self, *, map_priors: str = "marginal") -> tuple[sp.csc_matrix, list[int]]:
        """The graph's information matrix at the current values, and where each node is in it.

        The factors are linearised at the current estimates (robust losses at their current
        weights) and ``H = J^T J`` is formed from the sparse whitened Jacobian. Its rows and
        columns are ``(dx, dy, dtheta)`` of every variable in GTSAM's key order, each in the
        variable's own frame (``Pose2``'s retraction); ``columns[i]`` is the first column of
        node ``i``. The first node's prior fixes the gauge.

        ``map_priors`` says how the final refinement's scan-to-map priors
        (:meth:`add_map_prior`) count: ``"marginal"`` with their ``marginal_covariance`` (the
        directions the front end would trust; a prior without one is left out), ``"none"``
        not at all, ``"all"`` as optimised. They measure every node against one map the nodes
        drew: a direction each scan fixes only weakly (a corridor's far end wall) looks, summed
        over hundreds of nodes, as sure as a wall beside the robot, and a 40-60 m corridor's
        along-axis drift then looked like a centimetre.

        Returns
        -------
        H : scipy.sparse.csc_matrix of shape (3 V, 3 V)
        columns : list of int, length n_nodes
        """
        if map_priors not in ("marginal", "none", "all"):
            raise ConfigurationError(
                f"map_priors: expected 'marginal', 'none' or 'all', got {map_priors!r}"
            )
        graph = self.graph
        if map_priors != "all" and self._map_priors:
            graph = gtsam.NonlinearFactorGraph()
            for k in range(self.graph.size()):
                if not self.graph.exists(k):
                    continue
                if k not in self._map_priors:
                    graph.add(self.graph.at(k))
                    continue
                marginal = self._map_priors[k]
                if map_priors == "marginal" and marginal is not None:
                    graph.add(marginal)
        triplets = graph.linearize(self.values).sparseJacobian_()
        keys = sorted(int(k) for k in self.values.keys())  # noqa: SIM118 (gtsam.Values)
        n = 3 * len(keys)
        rows = triplets[0].astype(np.intp) - 1
        cols = triplets[1].astype(np.intp) - 1
        keep = cols < n  # the last column is the right-hand side
        jac = sp.csr_matrix(
            (triplets[2][keep], (rows[keep], cols[keep])), shape=(rows.max() + 1, n)
        )
        first = {k: 3 * c for c, k in enumerate(keys)}
        return (jac.T @ jac).tocsc(), [first[_node(i)] for i in range(self.n_nodes)]

    def optimize(self) -> float:
        """Run Levenberg-Marquardt from the current values; returns the final error."""
        prm = gtsam.LevenbergMarquardtParams()
        prm.setMaxIterations(int(self.params.max_iterations))
        opt = gtsam.LevenbergMarquardtOptimizer(self.graph, self.values, prm)
        self.values = opt.optimize()
        return float(self.graph.error(self.values))
