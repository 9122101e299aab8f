"""DBoW2's hierarchical k-means of binary descriptors (``TemplatedVocabulary::create``).

Each node's descriptors are clustered into ``k`` groups with k-means++ seeding, Hamming
distance and the bit-wise majority as cluster centre (``FORB::meanValue``: a bit is set when at
least ``ceil(n/2)`` of the n descriptors have it); the groups are clustered again down to ``L``
levels. Nodes are numbered as DBoW2 numbers them: the root is 0 and the children of a node are
created together, depth first, so an ORBvoc.txt-style file lists them in the same order.

Two things DBoW2 leaves undefined are fixed here and documented: a cluster that loses all its
descriptors keeps its previous centre (DBoW2 would take the mean of nothing), and
``max_iterations`` bounds the Lloyd iterations (DBoW2 iterates until no descriptor changes
cluster, which binary majority centres do not always reach; ``None`` restores that).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "HKMeansTree",
    "as_u64",
    "hamming_to_centres",
    "hierarchical_kmeans",
    "kmeans_pp_seeds",
    "majority_centre",
]


def as_u64(descriptors: NDArray[np.uint8]) -> NDArray[np.uint64]:
    """View ``(N, 32)`` uint8 descriptors as ``(N, 4)`` uint64 (for fast XOR + popcount)."""
    d = np.ascontiguousarray(descriptors, dtype=np.uint8)
    return d.view(np.uint64).reshape(d.shape[0], d.shape[1] // 8)


def hamming_to_centres(
    data64: NDArray[np.uint64], centres64: NDArray[np.uint64]
) -> NDArray[np.int32]:
    """Hamming distances ``(N, K)`` between ``(N, 4)`` and ``(K, 4)`` uint64 descriptors."""
    out = np.empty((data64.shape[0], centres64.shape[0]), np.int32)
    for j in range(centres64.shape[0]):
        out[:, j] = np.bitwise_count(data64 ^ centres64[j]).sum(axis=1, dtype=np.int32)
    return out


def majority_centre(descriptors: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """DBoW2's ``FORB::meanValue``: bit set when set in at least ``ceil(n/2)`` descriptors.

    Parameters
    ----------
    descriptors : (n, B) uint8, n >= 1

    Returns
    -------
    (B,) uint8
    """
    n = descriptors.shape[0]
    counts = np.unpackbits(descriptors, axis=1).sum(axis=0, dtype=np.int64)
    return np.packbits(counts >= (n // 2 + n % 2))


def kmeans_pp_seeds(
    data64: NDArray[np.uint64], k: int, rng: np.random.Generator
) -> NDArray[np.int64]:
    """DBoW2's ``initiateClusters`` (k-means++): indices of up to ``k`` seed descriptors.

    The first seed is uniform; each next one is drawn with probability proportional to its
    Hamming distance to the nearest seed so far (DBoW2 uses D(x), not D(x)^2, despite its
    comment). Stops early when every descriptor coincides with a seed.
    """
    n = data64.shape[0]
    seeds = [int(rng.integers(n))]
    min_d = np.bitwise_count(data64 ^ data64[seeds[0]]).sum(axis=1, dtype=np.int64).astype(float)
    while len(seeds) < k:
        csum = np.cumsum(min_d)
        total = csum[-1]
        if total <= 0:
            break
        cut = 0.0
        while cut == 0.0:
            cut = rng.uniform(0.0, total)
        idx = int(min(np.searchsorted(csum, cut, side="left"), n - 1))
        seeds.append(idx)
        d = np.bitwise_count(data64 ^ data64[idx]).sum(axis=1, dtype=np.int64)
        np.minimum(min_d, d, out=min_d)
    return np.array(seeds, np.int64)


def _kmeans(
    desc: NDArray[np.uint8],
    data64: NDArray[np.uint64],
    k: int,
    rng: np.random.Generator,
    max_iterations: int | None,
) -> tuple[NDArray[np.uint8], NDArray[np.int64]]:
    """Cluster n > k descriptors; return centres (c, 32) and the association (n,)."""
    centres = desc[kmeans_pp_seeds(data64, k, rng)].copy()
    last: NDArray[np.int64] | None = None
    it = 0
    while True:
        assoc = hamming_to_centres(data64, as_u64(centres)).argmin(axis=1).astype(np.int64)
        if last is not None and np.array_equal(assoc, last):
            break
        it += 1
        if max_iterations is not None and it > max_iterations:
            break
        last = assoc
        for c in range(centres.shape[0]):
            members = desc[assoc == c]
            if members.shape[0]:
                centres[c] = majority_centre(members)
    return centres, assoc


@dataclass(frozen=True)
class HKMeansTree:
    """The tree that :func:`hierarchical_kmeans` builds.

    Attributes
    ----------
    parent : (N,) int32
        Parent node of each node; -1 for the root (node 0).
    descriptors : (N, 32) uint8
        Cluster centres (zeros for the root).
    """

    parent: NDArray[np.int32]
    descriptors: NDArray[np.uint8]


def hierarchical_kmeans(
    descriptors: NDArray[np.uint8],
    k: int,
    L: int,
    rng: np.random.Generator,
    *,
    max_iterations: int | None = 100,
    on_node: Callable[[int], None] | None = None,
) -> HKMeansTree:
    """DBoW2's ``HKmeansStep`` recursion over all training descriptors.

    Parameters
    ----------
    descriptors : (T, 32) uint8
        All training descriptors.
    k, L : int
        Branching factor and depth.
    rng : numpy.random.Generator
    max_iterations : int or None
        Bound on Lloyd iterations per node (None: until convergence, as DBoW2).
    on_node : callable, optional
        Called with the number of descriptors of each clustered node (progress reporting).

    Returns
    -------
    HKMeansTree
    """
    desc = np.ascontiguousarray(descriptors, np.uint8)
    parents: list[int] = [-1]
    centres: list[NDArray[np.uint8]] = [np.zeros(desc.shape[1], np.uint8)]

    def step(parent_id: int, idx: NDArray[np.int64], level: int) -> None:
        if idx.size == 0:
            return
        sub = desc[idx]
        if idx.size <= k:
            clusters = sub
            groups = [np.array([i]) for i in range(idx.size)]
        else:
            clusters, assoc = _kmeans(sub, as_u64(sub), k, rng, max_iterations)
            order = np.argsort(assoc, kind="stable")
            bounds = np.searchsorted(assoc[order], np.arange(clusters.shape[0] + 1))
            groups = [order[bounds[c] : bounds[c + 1]] for c in range(clusters.shape[0])]
        if on_node is not None:
            on_node(int(idx.size))
        first = len(parents)
        for c in range(clusters.shape[0]):
            parents.append(parent_id)
            centres.append(np.asarray(clusters[c], np.uint8))
        if level < L:
            for c in range(clusters.shape[0]):
                if groups[c].size > 1:
                    step(first + c, idx[groups[c]], level + 1)

    step(0, np.arange(desc.shape[0], dtype=np.int64), 1)
    return HKMeansTree(
        np.array(parents, np.int32), np.array(centres, np.uint8).reshape(-1, desc.shape[1])
    )
