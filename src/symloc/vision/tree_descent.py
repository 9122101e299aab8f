"""Compiled parts of the BoW transform: the descent of binary descriptors through a vocabulary
tree, and the assembly of the BoW vector and direct index (numba, cached on disk).

DBoW2's ``TemplatedVocabulary::transform`` sends each feature from the root to a leaf, at each
level to the child whose descriptor is nearest in Hamming distance (the first such child on a
tie). :func:`descend` does that for all features of an image in one compiled loop: per feature
and level, ``k`` distances of four 64-bit XOR + popcount each, with no NumPy call per level.
The machine code is cached beside this file (``cache=True``) like :mod:`symloc.mcl.kernels`;
:func:`warm_up` compiles or loads it before a first image.

:func:`bow_parts` then groups the features by word (summing or taking the first weight) and by
direct-index node, in one pass each over the sorted ``key * N + feature`` (a stable order),
instead of ``np.unique``, ``np.bincount`` and a stable argsort per image.

:func:`descend_py` is the same loop in plain Python (the definition the kernel is compiled
from, with ``int.bit_count`` for the popcount); the tests check the kernel against it and
against the level-by-level NumPy descent it replaced.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any, cast

import numba
import numpy as np
from numba import types
from numba.core.extending import intrinsic, overload
from numpy.typing import NDArray

__all__ = ["bow_parts", "bow_parts_py", "descend", "descend_py", "popcount64", "warm_up"]

_LOG = logging.getLogger(__name__)


def popcount64(x: Any) -> int:
    """Number of set bits of a 64-bit unsigned integer (``llvm.ctpop`` when compiled)."""
    return int(x).bit_count()


@intrinsic
def _ctpop_u64(typingctx: Any, x: Any) -> Any:  # pragma: no cover - compiled only
    """``llvm.ctpop.i64`` of a 64-bit integer as an int64 (one ``popcnt`` on x86-64)."""
    if not isinstance(x, types.Integer) or getattr(x, "bitwidth", 0) != 64:
        return None
    sig = types.int64(x)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        return builder.ctpop(args[0])

    return sig, codegen


@overload(popcount64)
def _popcount64_overload(x: Any) -> Any:  # pragma: no cover - compiled only
    if isinstance(x, types.Integer) and getattr(x, "bitwidth", 0) == 64:

        def impl(x: Any) -> Any:
            return _ctpop_u64(x)  # type: ignore[call-arg]  # numba adds typingctx

        return impl
    return None


def descend_py(
    q64: NDArray[np.uint64],
    row_of: NDArray[np.int64],
    kid_ids: NDArray[np.int32],
    kid_desc64: NDArray[np.uint64],
    child_count: NDArray[np.int32],
    nid_level: int,
    cur: NDArray[np.int32],
    nid: NDArray[np.int32],
) -> None:
    """Descend every descriptor from the root to a leaf; results written to ``cur``, ``nid``.

    Parameters
    ----------
    q64 : ndarray of shape (N, 4), uint64
        The N descriptors (256 bits each) as four 64-bit words.
    row_of : ndarray of shape (n_nodes,), int64
        Row of each inner node in ``kid_ids`` / ``kid_desc64`` (-1 for a leaf).
    kid_ids : ndarray of shape (I, k), int32
        Children of each inner node in DBoW2's order (slots past ``child_count`` unused).
    kid_desc64 : ndarray of shape (I, k, 4), uint64
        The children's descriptors.
    child_count : ndarray of shape (n_nodes,), int32
        Children of each node (0 for a leaf).
    nid_level : int
        Level of the direct-index node (``L - levelsup``; <= 0: the root).
    cur : ndarray of shape (N,), int32
        Out: the leaf (word node) each descriptor reaches.
    nid : ndarray of shape (N,), int32
        Out: the node at level ``nid_level`` on the way (the leaf when it is shallower, the
        root when ``nid_level <= 0``).
    """
    n = q64.shape[0]
    for i in range(n):
        q0 = q64[i, 0]
        q1 = q64[i, 1]
        q2 = q64[i, 2]
        q3 = q64[i, 3]
        node = 0
        direct = 0
        level = 0
        while child_count[node] > 0:
            level += 1
            r = row_of[node]
            best_j = 0
            best_d = 1 << 30
            for j in range(child_count[node]):
                d = (
                    popcount64(kid_desc64[r, j, 0] ^ q0)
                    + popcount64(kid_desc64[r, j, 1] ^ q1)
                    + popcount64(kid_desc64[r, j, 2] ^ q2)
                    + popcount64(kid_desc64[r, j, 3] ^ q3)
                )
                if d < best_d:  # strict: the first nearest child on a tie, as DBoW2
                    best_d = d
                    best_j = j
            node = kid_ids[r, best_j]
            if level <= nid_level:
                direct = node
        cur[i] = node
        nid[i] = direct


descend = cast(
    Callable[..., None],
    numba.njit(cache=True, nogil=True, error_model="numpy")(descend_py),
)


def bow_parts_py(
    words: NDArray[np.int32], w: NDArray[np.float64], nid: NDArray[np.int32], sum_weights: bool
) -> tuple[
    NDArray[np.int32], NDArray[np.float64], NDArray[np.int32], NDArray[np.int64], NDArray[np.int32]
]:
    """The BoW vector (before normalisation) and the direct index of quantised features.

    Features with weight 0 (stop words) are left out, as DBoW2 does.

    Parameters
    ----------
    words : ndarray of shape (N,), int32
        Word of each feature.
    w : ndarray of shape (N,), float64
        Its weight.
    nid : ndarray of shape (N,), int32
        Its direct-index node.
    sum_weights : bool
        True: a word's value is the sum of its features' weights in feature order (TF,
        TF-IDF; as ``np.bincount``); False: the weight of its first feature (IDF, binary).

    Returns
    -------
    words : ndarray of shape (W,), int32
        The distinct words, increasing.
    values : ndarray of shape (W,), float64
    nodes : ndarray of shape (D,), int32
        The distinct direct-index nodes, increasing.
    indptr : ndarray of shape (D + 1,), int64
    indices : ndarray of shape (n,), int32
        The kept features grouped by node, increasing within a node.
    """
    n = words.shape[0]
    idx = np.empty(n, np.int32)
    k = 0
    for i in range(n):
        if w[i] > 0:
            idx[k] = i
            k += 1
    idx = idx[:k]
    # stable sorts as sorts of unique keys (key * n + feature): feature order within a key
    keys = np.empty(k, np.int64)
    for j in range(k):
        keys[j] = np.int64(words[idx[j]]) * n + idx[j]
    keys.sort()
    uniq = np.empty(k, np.int32)
    values = np.empty(k, np.float64)
    g = -1
    for j in range(k):
        word = keys[j] // n
        wt = w[keys[j] - word * n]
        if g < 0 or word != uniq[g]:
            g += 1
            uniq[g] = word
            values[g] = 0.0 + wt if sum_weights else wt
        elif sum_weights:
            values[g] += wt
    for j in range(k):
        keys[j] = np.int64(nid[idx[j]]) * n + idx[j]
    keys.sort()
    nodes = np.empty(k, np.int32)
    indptr = np.empty(k + 1, np.int64)
    indices = np.empty(k, np.int32)
    d = 0
    for pos in range(k):
        node = keys[pos] // n
        indices[pos] = keys[pos] - node * n
        if d == 0 or node != nodes[d - 1]:
            nodes[d] = node
            indptr[d] = pos
            d += 1
    indptr[d] = k
    return (
        uniq[: g + 1].copy(),
        values[: g + 1].copy(),
        nodes[:d].copy(),
        indptr[: d + 1].copy(),
        indices,
    )


bow_parts = cast(
    Callable[..., Any],
    numba.njit(cache=True, nogil=True, error_model="numpy")(bow_parts_py),
)


def warm_up() -> float:
    """Compile (or load from the cache) :func:`descend` and :func:`bow_parts` on a two-level
    toy tree.

    Returns
    -------
    float
        Wall time spent [s].
    """
    t0 = time.perf_counter()
    q64 = np.zeros((2, 4), np.uint64)
    row_of = np.array([0, -1, -1], np.int64)
    kid_ids = np.array([[1, 2]], np.int32)
    kid_desc64 = np.zeros((1, 2, 4), np.uint64)
    kid_desc64[0, 1] = np.uint64(0xFFFF)
    child_count = np.array([2, 0, 0], np.int32)
    cur = np.empty(2, np.int32)
    nid = np.empty(2, np.int32)
    descend(q64, row_of, kid_ids, kid_desc64, child_count, 1, cur, nid)
    bow_parts(cur - 1, np.ones(2), nid, True)
    spent = time.perf_counter() - t0
    _LOG.info("vocabulary descent kernel ready in %.2f s", spent)
    return spent
