"""Clustering particles into pose hypotheses (amcl's ``pf_cluster_stats``, fixed).

Particles are binned at ``0.5 m x 0.5 m x 10 deg`` (amcl's kd-tree histogram) and occupied bins
that touch (26-neighbourhood) are joined into clusters. Two fixes over nav2_amcl:

* the heading bins wrap: the bin just below +pi touches the bin just above -pi (nav2 splits a
  pose whose heading is near +-pi into two clusters);
* every cluster reports its *own* covariance (nav2 publishes the covariance of the whole
  particle set, however many clusters it holds).

A cluster's mean heading is the weighted circular mean; its heading variance is the circular
variance ``-2 ln R`` (R the mean resultant length), as amcl; the x-theta and y-theta
covariances use headings unwrapped around the circular mean. The work is linear in the number
of particles: compiled loops (:mod:`symloc.mcl.kernels`) put the bins in a hash table, join
touching bins by union-find, and add the moments as ``np.bincount`` would.
:func:`cluster_particles_reference` keeps the vectorised NumPy/SciPy definition (sorted unique
keys, ``connected_components``) that the compiled path reproduces bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.hypothesis import Hypothesis
from symloc.mcl import kernels

__all__ = [
    "BIN_ANGLE",
    "BIN_XY",
    "ClusterStats",
    "Hypothesis",
    "bin_indices",
    "bin_keys",
    "cluster_particles",
    "cluster_particles_reference",
]

FloatArray = NDArray[np.float64]

BIN_XY = 0.5
BIN_ANGLE = np.deg2rad(10.0)
N_ANGLE_BINS = 36


@dataclass(frozen=True, slots=True, eq=False)
class ClusterStats:
    """All clusters at once, heaviest first.

    ``labels (N,)`` gives each particle's cluster (index into the arrays below);
    ``weights (C,)``, ``means (C, 3)``, ``covariances (C, 3, 3)``, ``counts (C,)``.
    """

    labels: NDArray[np.intp]
    weights: FloatArray
    means: FloatArray
    covariances: FloatArray
    counts: NDArray[np.intp]

    def __len__(self) -> int:
        return int(self.weights.size)

    def hypotheses(self) -> list[Hypothesis]:
        """The clusters as :class:`~symloc.hypothesis.Hypothesis` records, heaviest first.

        Each carries its mean as ``pose``, its own ``covariance`` and ``n_particles``.
        """
        return [
            Hypothesis(pose=m, weight=float(w), covariance=c, n_particles=int(k))
            for w, m, c, k in zip(
                self.weights, self.means, self.covariances, self.counts, strict=True
            )
        ]


def bin_indices(particles: FloatArray) -> NDArray[np.int64]:
    """Integer bins ``(N, 3)``: floor(x / 0.5 m), floor(y / 0.5 m), heading bin 0..35."""
    p = np.asarray(particles, dtype=np.float64)
    out = np.empty((p.shape[0], 3), dtype=np.int64)
    out[:, 0] = np.floor(p[:, 0] / BIN_XY)
    out[:, 1] = np.floor(p[:, 1] / BIN_XY)
    out[:, 2] = np.floor((p[:, 2] + np.pi) / BIN_ANGLE).astype(np.int64) % N_ANGLE_BINS
    return out


def bin_keys(particles: FloatArray) -> NDArray[np.int64]:
    """One int64 key per particle identifying its bin (equal keys = same bin)."""
    b = bin_indices(particles)
    # 2^26 bins of 0.5 m in x and y each way is +-16,000 km: no collision for any map.
    return ((b[:, 0] + (1 << 25)) << 32) | ((b[:, 1] + (1 << 25)) << 6) | b[:, 2]


def _checked(particles: FloatArray, weights: FloatArray) -> tuple[FloatArray, FloatArray, float]:
    p = np.asarray(particles, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or w.shape != (p.shape[0],) or p.shape[0] == 0:
        raise ConfigurationError(
            f"particles/weights: expected shapes (N, 3) and (N,) with N > 0, got {p.shape}"
            f" and {w.shape}"
        )
    total = float(w.sum())
    if not np.isfinite(total) or total <= 0.0:
        raise ConfigurationError("weights: expected finite non-negative weights, positive sum")
    if not np.isfinite(p).all():
        raise ConfigurationError("particles: expected finite poses")
    return p, w, total


def cluster_particles(particles: FloatArray, weights: FloatArray) -> ClusterStats:
    """Cluster particles ``(N, 3)`` with weights ``(N,)`` (normalised inside) into hypotheses.

    Returns :class:`ClusterStats` sorted by weight, heaviest first. Linear in N (compiled);
    equal, bit for bit, to :func:`cluster_particles_reference`.
    """
    p, w, total = _checked(particles, weights)
    p = np.ascontiguousarray(p)
    w = np.ascontiguousarray(w)
    labels = np.empty(p.shape[0], dtype=np.int64)
    n = int(kernels.bin_components(p, BIN_XY, BIN_ANGLE, N_ANGLE_BINS, labels))
    first = np.empty((7, n))
    kernels.cluster_sums(p, w, total, labels, n, first)
    wsum, counts_f, mx, my, mc, ms = first[:6]
    mt = np.arctan2(ms, mc)
    second = np.empty((5, n))
    kernels.cluster_moments(p, w, total, labels, first, mt, second)
    rlen = np.clip(np.hypot(mc, ms), 1e-300, 1.0)
    cov = np.empty((n, 3, 3))
    cov[:, 0, 0] = second[0]
    cov[:, 1, 1] = second[1]
    cov[:, 0, 1] = cov[:, 1, 0] = second[2]
    cov[:, 0, 2] = cov[:, 2, 0] = second[3]
    cov[:, 1, 2] = cov[:, 2, 1] = second[4]
    cov[:, 2, 2] = -2.0 * np.log(rlen)
    means = np.column_stack([mx, my, np.pi - np.mod(np.pi - mt, 2.0 * np.pi)])
    counts = counts_f.astype(np.intp)
    order = np.argsort(-wsum, kind="stable")
    rank = np.empty(n, dtype=np.intp)
    rank[order] = np.arange(n)
    return ClusterStats(
        labels=rank[labels],
        weights=wsum[order],
        means=means[order],
        covariances=cov[order],
        counts=counts[order],
    )


def cluster_particles_reference(particles: FloatArray, weights: FloatArray) -> ClusterStats:
    """:func:`cluster_particles` in NumPy and SciPy alone: the definition it is tested against.

    ``np.unique`` on integer bin keys, ``np.searchsorted`` for the 26 neighbours,
    ``scipy.sparse.csgraph.connected_components``, ``np.bincount`` for the moments.
    """
    from scipy.sparse import coo_matrix  # the reference only: not imported with the filter
    from scipy.sparse.csgraph import connected_components

    p, w, total = _checked(particles, weights)
    w = w / total
    b = bin_indices(p)
    lo = b[:, :2].min(axis=0) - 1
    span = b[:, :2].max(axis=0) - lo + 2
    # Dense-enough keys with a one-bin margin so that neighbour keys never alias.
    key = ((b[:, 0] - lo[0]) * span[1] + (b[:, 1] - lo[1])) * N_ANGLE_BINS + b[:, 2]
    ukeys, inverse = np.unique(key, return_inverse=True)
    u = ukeys.size
    ub_t = ukeys % N_ANGLE_BINS
    ub_xy = ukeys // N_ANGLE_BINS
    rows: list[NDArray[np.intp]] = []
    cols: list[NDArray[np.intp]] = []
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dt in (-1, 0, 1):
                if (dx, dy, dt) <= (0, 0, 0):
                    continue  # each undirected edge once
                nkey = (ub_xy + dx * span[1] + dy) * N_ANGLE_BINS + (ub_t + dt) % N_ANGLE_BINS
                pos = np.searchsorted(ukeys, nkey)
                pos_c = np.minimum(pos, u - 1)
                found = ukeys[pos_c] == nkey
                if found.any():
                    rows.append(np.flatnonzero(found))
                    cols.append(pos_c[found])
    if rows:
        r = np.concatenate(rows)
        c = np.concatenate(cols)
        graph = coo_matrix((np.ones(r.size, dtype=np.int8), (r, c)), shape=(u, u))
        n_comp, comp = connected_components(graph, directed=False)
    else:
        n_comp, comp = u, np.arange(u)
    labels = comp[inverse]
    return _stats(p, w, labels, n_comp)


def _stats(p: FloatArray, w: FloatArray, labels: NDArray[np.intp], n: int) -> ClusterStats:
    wsum = np.asarray(np.bincount(labels, weights=w, minlength=n), dtype=np.float64)
    counts = np.bincount(labels, minlength=n)
    safe = np.where(wsum > 0, wsum, 1.0)
    # Normalise within a cluster; a zero-weight cluster falls back to equal weights.
    wn = np.where(wsum[labels] > 0, w / safe[labels], 1.0 / counts[labels])
    mx = np.bincount(labels, weights=wn * p[:, 0], minlength=n)
    my = np.bincount(labels, weights=wn * p[:, 1], minlength=n)
    mc = np.bincount(labels, weights=wn * np.cos(p[:, 2]), minlength=n)
    ms = np.bincount(labels, weights=wn * np.sin(p[:, 2]), minlength=n)
    mt = np.arctan2(ms, mc)
    rlen = np.clip(np.hypot(mc, ms), 1e-300, 1.0)
    dx = p[:, 0] - mx[labels]
    dy = p[:, 1] - my[labels]
    dt = np.pi - np.mod(np.pi - (p[:, 2] - mt[labels]), 2.0 * np.pi)
    cov = np.empty((n, 3, 3))
    cov[:, 0, 0] = np.bincount(labels, weights=wn * dx * dx, minlength=n)
    cov[:, 1, 1] = np.bincount(labels, weights=wn * dy * dy, minlength=n)
    cov[:, 0, 1] = cov[:, 1, 0] = np.bincount(labels, weights=wn * dx * dy, minlength=n)
    cov[:, 0, 2] = cov[:, 2, 0] = np.bincount(labels, weights=wn * dx * dt, minlength=n)
    cov[:, 1, 2] = cov[:, 2, 1] = np.bincount(labels, weights=wn * dy * dt, minlength=n)
    cov[:, 2, 2] = -2.0 * np.log(rlen)
    means = np.column_stack([mx, my, np.pi - np.mod(np.pi - mt, 2.0 * np.pi)])
    order = np.argsort(-wsum, kind="stable")
    rank = np.empty(n, dtype=np.intp)
    rank[order] = np.arange(n)
    return ClusterStats(
        labels=rank[labels],
        weights=wsum[order],
        means=means[order],
        covariances=cov[order],
        counts=counts[order],
    )
