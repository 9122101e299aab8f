"""DBoW2 scoring formulas against hand-computed values, and BoW containers."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError, DataFormatError
from symloc.vision.bow import (
    BowMatrix,
    BowVector,
    FeatureVector,
    Scoring,
    Weighting,
    parse_scoring,
    parse_weighting,
    score,
    score_many,
)

# two L1-normalised vectors sharing words 2 and 3
V = BowVector.from_dict({1: 0.5, 2: 0.3, 3: 0.2})
Wv = BowVector.from_dict({2: 0.5, 3: 0.25, 4: 0.25})


def test_l1_score_is_one_minus_half_l1_distance() -> None:
    # ||v - w||_1 = 0.5 + 0.2 + 0.05 + 0.25 = 1.0, so 1 - 0.5 * 1.0 = 0.5
    assert score(V, Wv, Scoring.L1_NORM) == pytest.approx(0.5)


def test_chi_square_score() -> None:
    expected = 2.0 * (0.3 * 0.5 / 0.8 + 0.2 * 0.25 / 0.45)
    assert score(V, Wv, Scoring.CHI_SQUARE) == pytest.approx(expected)
    assert expected == pytest.approx(0.5972222222)


def test_bhattacharyya_and_dot_product() -> None:
    assert score(V, Wv, Scoring.BHATTACHARYYA) == pytest.approx(math.sqrt(0.15) + math.sqrt(0.05))
    assert score(V, Wv, Scoring.DOT_PRODUCT) == pytest.approx(0.2)


def test_l2_score_uses_nister_scaling() -> None:
    a = BowVector.from_dict({1: 0.6, 2: 0.8})
    b = BowVector.from_dict({2: 0.6, 3: 0.8})
    assert score(a, b, Scoring.L2_NORM) == pytest.approx(1.0 - math.sqrt(1.0 - 0.48))
    assert score(a, a, Scoring.L2_NORM) == 1.0  # rounding guard: >= 1 gives exactly 1


def test_kl_score_counts_missing_words_with_log_eps() -> None:
    log_eps = math.log(sys.float_info.epsilon)
    expected = (
        0.5 * (math.log(0.5) - log_eps) + 0.3 * math.log(0.3 / 0.5) + 0.2 * math.log(0.2 / 0.25)
    )
    assert score(V, Wv, Scoring.KL) == pytest.approx(expected)
    # not symmetric: word 4 of w is missing from v
    expected_wv = (
        0.5 * math.log(0.5 / 0.3) + 0.25 * math.log(0.25 / 0.2) + 0.25 * (math.log(0.25) - log_eps)
    )
    assert score(Wv, V, Scoring.KL) == pytest.approx(expected_wv)


def test_identical_and_disjoint_vectors() -> None:
    other = BowVector.from_dict({7: 1.0})
    for sc in (Scoring.L1_NORM, Scoring.CHI_SQUARE, Scoring.BHATTACHARYYA):
        assert score(V, V, sc) == pytest.approx(1.0)
        assert score(V, other, sc) == 0.0


def test_score_many_matches_pairwise() -> None:
    db = [Wv, V, BowVector.from_dict({}), BowVector.from_dict({3: 1.0})]
    for sc in Scoring:
        many = score_many(V, BowMatrix.stack(db), sc)
        assert many == pytest.approx([score(V, b, sc) for b in db])


@settings(max_examples=40, deadline=None)
@given(
    st.dictionaries(st.integers(0, 30), st.floats(0.01, 1.0), min_size=1, max_size=12),
    st.dictionaries(st.integers(0, 30), st.floats(0.01, 1.0), min_size=1, max_size=12),
)
def test_l1_score_equals_dense_formula(a: dict[int, float], b: dict[int, float]) -> None:
    va = np.zeros(31)
    vb = np.zeros(31)
    va[list(a)] = list(a.values())
    vb[list(b)] = list(b.values())
    va /= va.sum()
    vb /= vb.sum()
    bv_a = BowVector(np.flatnonzero(va).astype(np.int32), va[va > 0])
    bv_b = BowVector(np.flatnonzero(vb).astype(np.int32), vb[vb > 0])
    assert score(bv_a, bv_b, "l1") == pytest.approx(1.0 - 0.5 * np.abs(va - vb).sum(), abs=1e-12)


def test_parse_names_and_codes() -> None:
    assert parse_weighting("tf-idf") is Weighting.TF_IDF
    assert parse_weighting(3) is Weighting.BINARY
    assert parse_scoring("l2") is Scoring.L2_NORM
    assert parse_scoring("CHI_SQUARE") is Scoring.CHI_SQUARE
    with pytest.raises(ConfigurationError, match="weighting: expected one of"):
        parse_weighting("tfidf2")
    with pytest.raises(ConfigurationError, match="scoring: expected one of"):
        parse_scoring(6)


def test_bow_vector_validation() -> None:
    with pytest.raises(DataFormatError, match="strictly increasing"):
        BowVector(np.array([2, 1]), np.array([0.5, 0.5]))
    with pytest.raises(DataFormatError, match="2 words but 1 values"):
        BowVector(np.array([1, 2]), np.array([0.5]))


def test_feature_vector_groups_by_node() -> None:
    fv = FeatureVector.from_assignment(
        np.array([5, 3, 5, 9, 3]), np.array([True, True, True, False, True])
    )
    assert fv.as_dict() == {3: [1, 4], 5: [0, 2]}
    assert fv.get(9).size == 0
    assert fv.get(5).tolist() == [0, 2]


def _dbow2_reference(v: dict[int, float], w: dict[int, float], sc: Scoring) -> float:
    """A literal transcription of DBoW2's merge-walk scoring loops, for comparison."""
    log_eps = math.log(sys.float_info.epsilon)
    common = sorted(set(v) & set(w))
    if sc == Scoring.L1_NORM:
        return -sum(abs(v[i] - w[i]) - abs(v[i]) - abs(w[i]) for i in common) / 2.0
    if sc == Scoring.L2_NORM:
        s = sum(v[i] * w[i] for i in common)
        return 1.0 if s >= 1 else 1.0 - math.sqrt(1.0 - s)
    if sc == Scoring.CHI_SQUARE:
        return 2.0 * sum(v[i] * w[i] / (v[i] + w[i]) for i in common if v[i] + w[i] != 0)
    if sc == Scoring.KL:
        return sum(
            v[i] * math.log(v[i] / w[i]) if i in w else v[i] * (math.log(v[i]) - log_eps)
            for i in sorted(v)
        )
    if sc == Scoring.BHATTACHARYYA:
        return sum(math.sqrt(v[i] * w[i]) for i in common)
    return sum(v[i] * w[i] for i in common)


@settings(max_examples=30, deadline=None)
@given(
    st.lists(
        st.dictionaries(st.integers(0, 40), st.floats(0.01, 1.0), min_size=1, max_size=15),
        min_size=2,
        max_size=6,
    )
)
def test_score_many_matches_dbow2_loops(vectors: list[dict[int, float]]) -> None:
    bows = [BowVector.from_dict(d) for d in vectors]
    for sc in Scoring:
        got = score_many(bows[0], BowMatrix.stack(bows), sc)
        want = [_dbow2_reference(vectors[0], d, sc) for d in vectors]
        assert got == pytest.approx(want, rel=1e-9, abs=1e-12)
