"""Bag-of-words vectors, DBoW2's weighting and scoring types, and its six scoring formulas.

The formulas are DBoW2's (Galvez-Lopez and Tardos, 2012), including their normalisations and
their quirks, so that scores can be compared with DBoW2/DBoW3/ORB-SLAM numbers:

- L1 (default): vectors L1-normalised; ``s = -1/2 * sum_common(|v-w| - |v| - |w|)`` in [0, 1].
- L2: L2-normalised; ``d = sum_common(v*w)``; ``s = 1 - sqrt(1 - d)`` (1 when d >= 1).
- chi-square: L1-normalised; ``s = 2 * sum_common(v*w / (v+w))``.
- KL: L1-normalised; ``s = sum_{i in v}( v_i log(v_i / w_i) if w_i != 0 else v_i (log v_i - log eps))``
  with eps the double epsilon; not symmetric and not scaled.
- Bhattacharyya: L1-normalised; ``s = sum_common sqrt(v*w)``.
- dot product: not normalised; ``s = sum_common v*w``.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError, DataFormatError

__all__ = [
    "BowMatrix",
    "BowVector",
    "FeatureVector",
    "Scoring",
    "Weighting",
    "normalization_of",
    "normalize_values",
    "parse_scoring",
    "parse_weighting",
    "score",
    "score_many",
]

#: ``log(DBL_EPSILON)`` as DBoW2's KL scoring uses it.
LOG_EPS = float(np.log(sys.float_info.epsilon))


class Weighting(IntEnum):
    """DBoW2's ``WeightingType`` (same integer codes as its files)."""

    TF_IDF = 0
    TF = 1
    IDF = 2
    BINARY = 3


class Scoring(IntEnum):
    """DBoW2's ``ScoringType`` (same integer codes as its files)."""

    L1_NORM = 0
    L2_NORM = 1
    CHI_SQUARE = 2
    KL = 3
    BHATTACHARYYA = 4
    DOT_PRODUCT = 5


_WEIGHTING_ALIASES = {
    "tfidf": Weighting.TF_IDF,
    "tf_idf": Weighting.TF_IDF,
    "tf-idf": Weighting.TF_IDF,
}
_SCORING_ALIASES = {
    "l1": Scoring.L1_NORM,
    "l2": Scoring.L2_NORM,
    "chi2": Scoring.CHI_SQUARE,
    "chi_square": Scoring.CHI_SQUARE,
    "chi-square": Scoring.CHI_SQUARE,
    "kl": Scoring.KL,
    "bhattacharyya": Scoring.BHATTACHARYYA,
    "dot": Scoring.DOT_PRODUCT,
    "dot_product": Scoring.DOT_PRODUCT,
}


def parse_weighting(value: Weighting | int | str) -> Weighting:
    """Return a :class:`Weighting` from an enum, DBoW2 integer code or name (``"tf-idf"``)."""
    if isinstance(value, str):
        key = value.strip().lower()
        if key in _WEIGHTING_ALIASES:
            return _WEIGHTING_ALIASES[key]
        try:
            return Weighting[key.upper()]
        except KeyError:
            pass
    elif isinstance(value, (int, np.integer)) and 0 <= int(value) <= 3:
        return Weighting(int(value))
    raise ConfigurationError(
        f"weighting: expected one of TF_IDF(0), TF(1), IDF(2), BINARY(3), got {value!r}"
    )


def parse_scoring(value: Scoring | int | str) -> Scoring:
    """Return a :class:`Scoring` from an enum, DBoW2 integer code or name (``"l1"``)."""
    if isinstance(value, str):
        key = value.strip().lower()
        if key in _SCORING_ALIASES:
            return _SCORING_ALIASES[key]
        try:
            return Scoring[key.upper()]
        except KeyError:
            pass
    elif isinstance(value, (int, np.integer)) and 0 <= int(value) <= 5:
        return Scoring(int(value))
    raise ConfigurationError(
        "scoring: expected one of L1_NORM(0), L2_NORM(1), CHI_SQUARE(2), KL(3), "
        f"BHATTACHARYYA(4), DOT_PRODUCT(5), got {value!r}"
    )


def normalization_of(scoring: Scoring) -> str | None:
    """Return the norm DBoW2 applies before ``scoring`` (``"l1"``, ``"l2"`` or None)."""
    if scoring == Scoring.L2_NORM:
        return "l2"
    if scoring == Scoring.DOT_PRODUCT:
        return None
    return "l1"


def normalize_values(values: NDArray[np.float64], norm: str) -> NDArray[np.float64]:
    """DBoW2's ``BowVector::normalize``: divide by the L1 or L2 norm when it is > 0."""
    n = float(np.abs(values).sum()) if norm == "l1" else float(np.sqrt(np.dot(values, values)))
    return values / n if n > 0.0 else values


@dataclass(frozen=True)
class BowVector:
    """A sparse bag-of-words vector (DBoW2's ``BowVector``: word id -> value).

    Attributes
    ----------
    words : (n,) int32
        Word ids, strictly increasing.
    values : (n,) float64
        Word values (weights).
    """

    words: NDArray[np.int32]
    values: NDArray[np.float64]

    def __post_init__(self) -> None:
        w = np.ascontiguousarray(self.words, dtype=np.int32).reshape(-1)
        v = np.ascontiguousarray(self.values, dtype=np.float64).reshape(-1)
        if w.shape != v.shape:
            raise DataFormatError(f"BowVector: {w.size} words but {v.size} values")
        if w.size > 1 and np.any(np.diff(w) <= 0):
            raise DataFormatError("BowVector.words: expected strictly increasing word ids")
        object.__setattr__(self, "words", w)
        object.__setattr__(self, "values", v)

    def __len__(self) -> int:
        return int(self.words.size)

    @classmethod
    def from_dict(cls, mapping: dict[int, float]) -> BowVector:
        """Build from a ``{word_id: value}`` mapping."""
        items = sorted(mapping.items())
        return cls(
            np.array([k for k, _ in items], np.int32), np.array([v for _, v in items], np.float64)
        )

    def to_dict(self) -> dict[int, float]:
        """Return the vector as a ``{word_id: value}`` dict."""
        return {int(k): float(v) for k, v in zip(self.words, self.values, strict=True)}


@dataclass(frozen=True)
class FeatureVector:
    """DBoW2's ``FeatureVector`` (direct index): node id -> indices of the features under it.

    Attributes
    ----------
    nodes : (m,) int32
        Node ids, strictly increasing.
    indptr : (m + 1,) int64
        Features of ``nodes[i]`` are ``indices[indptr[i]:indptr[i+1]]``.
    indices : (n,) int32
        Feature indices (increasing within a node).
    """

    nodes: NDArray[np.int32]
    indptr: NDArray[np.int64]
    indices: NDArray[np.int32]

    def __len__(self) -> int:
        return int(self.nodes.size)

    def get(self, node: int) -> NDArray[np.int32]:
        """Return the feature indices stored under ``node`` (empty if none)."""
        i = int(np.searchsorted(self.nodes, node))
        if i < self.nodes.size and self.nodes[i] == node:
            return self.indices[self.indptr[i] : self.indptr[i + 1]]
        return np.zeros(0, np.int32)

    def as_dict(self) -> dict[int, list[int]]:
        """Return ``{node_id: [feature indices]}``."""
        return {
            int(n): self.indices[self.indptr[i] : self.indptr[i + 1]].tolist()
            for i, n in enumerate(self.nodes)
        }

    @classmethod
    def from_assignment(
        cls, node_of_feature: NDArray[Any], keep: NDArray[np.bool_]
    ) -> FeatureVector:
        """Group feature indices by node (features with ``keep`` False are left out)."""
        idx = np.flatnonzero(keep).astype(np.int32)
        nodes_all = np.asarray(node_of_feature)[idx]
        order = np.argsort(nodes_all, kind="stable")
        sorted_nodes = nodes_all[order]
        nodes, starts = np.unique(sorted_nodes, return_index=True)
        indptr = np.append(starts, sorted_nodes.size).astype(np.int64)
        return cls(nodes.astype(np.int32), indptr, idx[order])


@dataclass(frozen=True)
class BowMatrix:
    """Many BoW vectors stacked row by row (CSR layout) for scoring a query against all at once.

    Attributes
    ----------
    indptr : (n + 1,) int64
    words : (nnz,) int32
    values : (nnz,) float64
    """

    indptr: NDArray[np.int64]
    words: NDArray[np.int32]
    values: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.indptr.size - 1)

    @classmethod
    def stack(cls, vectors: Sequence[BowVector]) -> BowMatrix:
        """Stack BoW vectors (row i is ``vectors[i]``)."""
        lengths = np.array([len(v) for v in vectors], np.int64)
        indptr = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        if vectors:
            words = np.concatenate([v.words for v in vectors]).astype(np.int32)
            values = np.concatenate([v.values for v in vectors]).astype(np.float64)
        else:
            words, values = np.zeros(0, np.int32), np.zeros(0, np.float64)
        return cls(indptr, words, values)

    @cached_property
    def _inverted(self) -> tuple[NDArray[np.int32], NDArray[np.int64], NDArray[np.int64]]:
        order = np.argsort(self.words, kind="stable")
        rows = np.repeat(np.arange(len(self), dtype=np.int64), np.diff(self.indptr))
        return self.words[order], order.astype(np.int64), rows

    def inverted(self) -> tuple[NDArray[np.int32], NDArray[np.int64], NDArray[np.int64]]:
        """The inverted index: sorted words, their positions in ``words``, and each entry's row.

        Built on first use and kept (the matrix is immutable)."""
        return self._inverted

    def row(self, i: int) -> BowVector:
        """Return row ``i`` as a :class:`BowVector`."""
        a, b = self.indptr[i], self.indptr[i + 1]
        return BowVector(self.words[a:b], self.values[a:b])


def score_many(
    query: BowVector, database: BowMatrix | Sequence[BowVector], scoring: Scoring | int | str
) -> NDArray[np.float64]:
    """DBoW2 score of ``query`` (as ``v1``) against every row of ``database`` (as ``v2``).

    Only words present in both vectors contribute (plus, for KL, a term of the query alone), so
    the rows are found through an inverted index (word -> rows), as DBoW2's database does.

    Parameters
    ----------
    query : BowVector
        Normalised as the scoring requires (as :meth:`Vocabulary.transform` returns it).
    database : BowMatrix or sequence of BowVector
        n vectors, normalised the same way.
    scoring : Scoring
        One of DBoW2's six scorings.

    Returns
    -------
    (n,) float64
        ``score(query, database[i])``.
    """
    sc = parse_scoring(scoring)
    db = database if isinstance(database, BowMatrix) else BowMatrix.stack(list(database))
    n = len(db)
    sorted_words, order, row_of = db.inverted()
    lo = np.searchsorted(sorted_words, query.words, side="left")
    hi = np.searchsorted(sorted_words, query.words, side="right")
    counts = hi - lo
    total = int(counts.sum())
    ends = np.cumsum(counts)
    pos = np.repeat(lo - (ends - counts), counts) + np.arange(total)
    hit = order[pos]
    rows = row_of[hit]
    w = db.values[hit]
    v = np.repeat(query.values, counts)
    if sc == Scoring.L1_NORM:
        c = np.abs(v - w) - np.abs(v) - np.abs(w)
        return np.asarray(-0.5 * np.bincount(rows, weights=c, minlength=n), np.float64)
    if sc in (Scoring.L2_NORM, Scoring.DOT_PRODUCT):
        s = np.asarray(np.bincount(rows, weights=v * w, minlength=n), np.float64)
        if sc == Scoring.DOT_PRODUCT:
            return s
        out = np.ones(n)
        lt = s < 1.0
        out[lt] = 1.0 - np.sqrt(1.0 - s[lt])
        return out
    if sc == Scoring.CHI_SQUARE:
        den = v + w
        ok = den != 0.0
        c = np.where(ok, v * w / np.where(ok, den, 1.0), 0.0)
        return np.asarray(2.0 * np.bincount(rows, weights=c, minlength=n), np.float64)
    if sc == Scoring.BHATTACHARYYA:
        return np.asarray(
            np.bincount(rows, weights=np.sqrt(np.abs(v * w)), minlength=n), np.float64
        )
    # KL: every query word counts; words missing from the entry cost v (log v - log eps).
    qv = query.values
    with np.errstate(divide="ignore", invalid="ignore"):
        base = float(np.where(qv != 0.0, qv * (np.log(np.abs(qv)) - LOG_EPS), 0.0).sum())
        both = (v != 0.0) & (w != 0.0)
        only_v = (v != 0.0) & (w == 0.0)
        safe_v = np.where(both | only_v, v, 1.0)
        safe_w = np.where(both, w, 1.0)
        miss = safe_v * (np.log(np.abs(safe_v)) - LOG_EPS)
        c = np.where(both, safe_v * np.log(safe_v / safe_w) - miss, 0.0) - np.where(
            only_v, miss, 0.0
        )
    return np.asarray(base + np.bincount(rows, weights=c, minlength=n), np.float64)


def score(a: BowVector, b: BowVector, scoring: Scoring | int | str) -> float:
    """DBoW2's ``GeneralScoring::score(a, b)`` for one pair (see the module docstring)."""
    return float(score_many(a, BowMatrix.stack([b]), scoring)[0])
