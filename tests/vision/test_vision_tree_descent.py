"""The compiled vocabulary descent and the BoW transform: bit-identical to the NumPy descent.

``_quantize_numpy`` and ``_transform_numpy`` are the level-by-level NumPy implementation that
``Vocabulary.quantize`` / ``Vocabulary.transform`` used before the numba kernel (main
bad82ae), kept here verbatim as the reference: every word, weight, direct-index node, BoW
value and feature-vector entry must be equal bit for bit on seeded descriptors, for full and
ragged trees, every weighting and scoring, and several ``levelsup``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from symloc.vision.bow import (
    BowVector,
    FeatureVector,
    Scoring,
    Weighting,
    normalization_of,
    normalize_values,
)
from symloc.vision.hkmeans import as_u64
from symloc.vision.tree_descent import (
    bow_parts,
    bow_parts_py,
    descend,
    descend_py,
    popcount64,
    warm_up,
)
from symloc.vision.vocabulary import Vocabulary


def _quantize_numpy(
    voc: Vocabulary, descriptors: np.ndarray, levelsup: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``Vocabulary.quantize`` as it was before the kernel (the NumPy level-by-level descent)."""
    desc = np.ascontiguousarray(descriptors)
    n = desc.shape[0]
    cur = np.zeros(n, np.int32)
    nid = np.zeros(n, np.int32)
    nid_level = voc.L - int(levelsup)
    if voc.n_nodes == 1 or n == 0:
        return np.full(n, -1, np.int32), np.zeros(n), nid
    row_of, kid_ids, kid_desc64, kid_penalty = voc._descent_index()
    q64 = as_u64(desc)
    active = np.arange(n)
    qa = q64
    level = 0
    while active.size:
        level += 1
        rows = row_of[cur[active]]
        x = np.bitwise_count(kid_desc64[rows] ^ qa[:, None, :])
        dist = (x[..., 0] + x[..., 1] + x[..., 2] + x[..., 3]).astype(np.int32)
        dist += kid_penalty[rows]
        best = kid_ids[rows, dist.argmin(axis=1)]
        cur[active] = best
        if level <= nid_level:
            nid[active] = best
        keep = voc.child_count[best] > 0
        if not keep.all():
            active = active[keep]
            qa = qa[keep]
    return voc.word_of_node[cur], voc.weights[cur], nid


def _transform_numpy(
    voc: Vocabulary, descriptors: np.ndarray, levelsup: int = 0
) -> tuple[BowVector, FeatureVector]:
    """``Vocabulary.transform`` as it was before the kernels."""
    words, w, nid = _quantize_numpy(voc, descriptors, levelsup)
    keep = w > 0
    kw = words[keep]
    uniq, inv = np.unique(kw, return_inverse=True)
    if voc.weighting in (Weighting.TF, Weighting.TF_IDF):
        values = np.bincount(inv, weights=w[keep], minlength=uniq.size).astype(np.float64)
    else:
        first = np.zeros(uniq.size, np.int64)
        first[inv[::-1]] = np.arange(kw.size)[::-1]
        values = w[keep][first] if uniq.size else np.zeros(0)
    norm = normalization_of(voc.scoring)
    if norm is None:
        if voc.weighting in (Weighting.TF, Weighting.TF_IDF) and uniq.size:
            values = values / float(uniq.size)
    else:
        values = normalize_values(values, norm)
    return BowVector(uniq.astype(np.int32), values), FeatureVector.from_assignment(nid, keep)


def _tree(
    k: int, levels: int, rng: np.random.Generator, *, ragged: bool, weighting: Any, scoring: Any
) -> Vocabulary:
    """A random tree: full (every inner node has k children) or ragged (1..k children, leaves
    at several depths), with some zero weights (stop words) and repeated child descriptors
    (ties in the Hamming distance)."""
    parent = [-1]
    frontier = [0]
    for level in range(levels):
        nxt = []
        for node in frontier:
            n_kids = k if not ragged else int(rng.integers(1, k + 1))
            if ragged and level > 0 and rng.random() < 0.2:
                continue  # a leaf above the last level
            for _ in range(n_kids):
                parent.append(node)
                nxt.append(len(parent) - 1)
        frontier = nxt
    n = len(parent)
    desc = rng.integers(0, 256, (n, 32), dtype=np.uint8)
    dup = rng.integers(1, n, n // 10)
    desc[dup] = desc[np.maximum(dup - 1, 1)]  # siblings with equal descriptors: ties
    weights = rng.uniform(0.0, 3.0, n)
    weights[rng.random(n) < 0.1] = 0.0
    return Vocabulary(k, levels, weighting, scoring, np.array(parent), desc, weights)


def _assert_same(voc: Vocabulary, d: np.ndarray, levelsup: int) -> None:
    ref_q: tuple[np.ndarray, ...] = _quantize_numpy(voc, d, levelsup)
    new_q: tuple[np.ndarray, ...] = voc.quantize(d, levelsup)
    for a, b in zip(ref_q, new_q, strict=True):
        assert a.dtype == b.dtype
        assert np.array_equal(a, b)
    ref_bow, ref_fv = _transform_numpy(voc, d, levelsup)
    bow, fv = voc.transform(d, levelsup)
    assert np.array_equal(bow.words, ref_bow.words)
    assert bow.values.tobytes() == ref_bow.values.tobytes()  # bit for bit
    for a, b in (
        (bow.words, ref_bow.words),
        (fv.nodes, ref_fv.nodes),
        (fv.indptr, ref_fv.indptr),
        (fv.indices, ref_fv.indices),
    ):
        assert a.dtype == b.dtype
        assert np.array_equal(a, b)


@pytest.mark.parametrize("ragged", [False, True])
@pytest.mark.parametrize("weighting", list(Weighting))
@pytest.mark.parametrize("scoring", list(Scoring))
def test_transform_is_bit_identical_to_the_numpy_descent(
    ragged: bool, weighting: Weighting, scoring: Scoring
) -> None:
    rng = np.random.default_rng(1000 * int(weighting) + 10 * int(scoring) + int(ragged))
    voc = _tree(6, 3, rng, ragged=ragged, weighting=weighting, scoring=scoring)
    for n in (0, 1, 7, 500):
        d = rng.integers(0, 256, (n, 32), dtype=np.uint8)
        if n > 1:
            d[: n // 4] = voc.descriptors[rng.integers(1, voc.n_nodes, n // 4)]  # exact hits
        for levelsup in (0, 1, 2, 5):
            _assert_same(voc, d, levelsup)


def test_transform_is_bit_identical_on_a_deep_full_tree_and_real_orb_shape() -> None:
    """k=10, L=4 full tree (10,000 words), 1,000 descriptors, the ORB-SLAM levelsup 4 too."""
    rng = np.random.default_rng(7)
    voc = _tree(10, 4, rng, ragged=False, weighting="tf-idf", scoring="l1")
    d = rng.integers(0, 256, (1000, 32), dtype=np.uint8)
    for levelsup in (0, 4):
        _assert_same(voc, d, levelsup)


def test_kernel_matches_its_python_definition() -> None:
    rng = np.random.default_rng(3)
    voc = _tree(5, 3, rng, ragged=True, weighting="tf-idf", scoring="l1")
    d = rng.integers(0, 256, (40, 32), dtype=np.uint8)
    row_of, kid_ids, kid_desc64, _ = voc._descent_index()
    outs = []
    for fn in (descend, descend_py):
        cur = np.empty(40, np.int32)
        nid = np.empty(40, np.int32)
        fn(as_u64(d), row_of, kid_ids, kid_desc64, voc.child_count, 2, cur, nid)
        outs.append((cur, nid))
    assert np.array_equal(outs[0][0], outs[1][0])
    assert np.array_equal(outs[0][1], outs[1][1])


def test_bow_parts_kernel_matches_its_python_definition() -> None:
    rng = np.random.default_rng(4)
    for n in (0, 1, 50):
        words = rng.integers(0, 12, n).astype(np.int32)
        w = np.where(rng.random(n) < 0.2, 0.0, rng.uniform(0.1, 2.0, n))
        nid = rng.integers(0, 5, n).astype(np.int32)
        for sum_weights in (True, False):
            got: tuple[np.ndarray, ...] = bow_parts(words, w, nid, sum_weights)
            want: tuple[np.ndarray, ...] = bow_parts_py(words, w, nid, sum_weights)
            for a, b in zip(got, want, strict=True):
                assert a.dtype == b.dtype
                assert a.tobytes() == b.tobytes()


def test_popcount64_and_warm_up() -> None:
    assert popcount64(np.uint64(0xFFFF_0000_0000_0001)) == 17
    assert popcount64(np.uint64(0)) == 0
    assert warm_up() >= 0.0
