"""Compiled descent of binary descriptors through a vocabulary tree (numba, cached on disk).

DBoW2's ``TemplatedVocabulary::transform`` sends each feature from the root to a leaf, at each
level to the child whose descriptor is nearest in Hamming distance (the first such child on a
tie). :func:`descend` does that for all features of an image in one compiled loop: per feature
and level, ``k`` distances of four 64-bit XOR + popcount each, with no NumPy call per level.
The machine code is cached beside this file (``cache=True``) like :mod:`symloc.mcl.kernels`;
:func:`warm_up` compiles or loads it before a first image.

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

__all__ = ["descend", "descend_py", "popcount64", "warm_up"]

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


def warm_up() -> float:
    """Compile (or load from the cache) :func:`descend` on a two-level toy tree.

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
    spent = time.perf_counter() - t0
    _LOG.info("vocabulary descent kernel ready in %.2f s", spent)
    return spent
