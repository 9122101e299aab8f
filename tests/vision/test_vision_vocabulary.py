"""Hierarchical k-means (majority centres, k-means++), transform semantics, weights."""

from __future__ import annotations

import numpy as np
import pytest
import vision_helpers as helpers

from symloc.errors import ConfigurationError, DataFormatError
from symloc.vision.bow import Scoring, Weighting
from symloc.vision.hkmeans import as_u64, hamming_to_centres, kmeans_pp_seeds, majority_centre
from symloc.vision.vocabulary import Vocabulary


def _desc(bits_set: list[int]) -> np.ndarray:
    """A 32-byte descriptor with the given bit positions (MSB-first, as DBoW2 counts) set."""
    bits = np.zeros(256, np.uint8)
    bits[bits_set] = 1
    return np.packbits(bits)


def test_majority_centre_sets_bit_at_half_or_more() -> None:
    d = np.stack([_desc([0, 1, 2]), _desc([0, 1]), _desc([0, 5]), _desc([7])])
    # n=4: a bit needs >= 2 votes: bit 0 (3 votes), bit 1 (2 votes) set; 2, 5, 7 (1 vote) not
    c = np.unpackbits(majority_centre(d))
    assert np.flatnonzero(c).tolist() == [0, 1]
    # n=3: needs >= 2 votes
    c3 = np.unpackbits(majority_centre(d[:3]))
    assert np.flatnonzero(c3).tolist() == [0, 1]
    # n=1: the descriptor itself
    assert np.array_equal(majority_centre(d[3:]), d[3])


def test_hamming_distances() -> None:
    a = np.stack([_desc([0, 1, 2]), _desc([])])
    b = np.stack([_desc([0]), _desc(list(range(256)))])
    assert hamming_to_centres(as_u64(a), as_u64(b)).tolist() == [[2, 253], [1, 256]]


def test_kmeans_pp_seeds_are_distinct_and_stop_on_duplicates() -> None:
    rng = np.random.default_rng(0)
    data = rng.integers(0, 256, (50, 32), dtype=np.uint8)
    seeds = kmeans_pp_seeds(as_u64(data), 10, rng)
    assert len(set(seeds.tolist())) == 10
    same = np.repeat(data[:1], 20, axis=0)
    assert len(kmeans_pp_seeds(as_u64(same), 5, rng)) == 1


def _tiny_vocabulary(weighting: Weighting, scoring: Scoring) -> Vocabulary:
    """k=2, L=2: root 0 -> 1, 2; 1 -> 3, 4; 2 -> 5, 6 (words 0..3 = nodes 3..6)."""
    d = np.zeros((7, 32), np.uint8)
    d[1] = _desc([])
    d[2] = _desc(list(range(128, 256)))
    d[3] = _desc([])
    d[4] = _desc(list(range(40)))
    d[5] = _desc(list(range(128, 256)))
    d[6] = _desc(list(range(128, 256)) + list(range(40)))
    parent = [-1, 0, 0, 1, 1, 2, 2]
    weights = [0, 0, 0, 0.5, 1.0, 0.0, 2.0]
    return Vocabulary(2, 2, weighting, scoring, parent, d, weights)


FEATS = np.stack(
    [
        _desc([1]),  # -> node 3 (word 0)
        _desc([2, 3]),  # -> node 3 (word 0)
        _desc(list(range(38))),  # -> node 4 (word 1)
        _desc(list(range(130, 256))),  # -> node 5 (word 2, weight 0: stop word)
        _desc(list(range(128, 256)) + list(range(41))),  # -> node 6 (word 3)
    ]
)


def test_quantize_descends_to_nearest_words() -> None:
    voc = _tiny_vocabulary(Weighting.TF_IDF, Scoring.L1_NORM)
    words, w, nid = voc.quantize(FEATS, levelsup=1)
    assert words.tolist() == [0, 0, 1, 2, 3]
    assert w.tolist() == [0.5, 0.5, 1.0, 0.0, 2.0]
    assert nid.tolist() == [1, 1, 1, 2, 2]  # level L - 1 = 1


def test_transform_tf_idf_l1_sums_weights_and_drops_stop_words() -> None:
    voc = _tiny_vocabulary(Weighting.TF_IDF, Scoring.L1_NORM)
    bow, fv = voc.transform(FEATS)
    # word 0: 0.5 + 0.5, word 1: 1.0, word 3: 2.0; total 4
    assert bow.to_dict() == pytest.approx({0: 0.25, 1: 0.25, 3: 0.5})
    assert fv.as_dict() == {3: [0, 1], 4: [2], 6: [4]}


def test_transform_tf_without_normalising_scoring_divides_by_distinct_words() -> None:
    voc = _tiny_vocabulary(Weighting.TF_IDF, Scoring.DOT_PRODUCT)
    bow, _ = voc.transform(FEATS)
    assert bow.to_dict() == pytest.approx({0: 1 / 3, 1: 1 / 3, 3: 2 / 3})


def test_transform_idf_and_binary_take_each_word_once() -> None:
    voc = _tiny_vocabulary(Weighting.IDF, Scoring.L2_NORM)
    bow, _ = voc.transform(FEATS)
    raw = np.array([0.5, 1.0, 2.0])
    assert bow.values == pytest.approx(raw / np.linalg.norm(raw))
    assert bow.words.tolist() == [0, 1, 3]


def test_transform_of_no_features_is_empty() -> None:
    voc = _tiny_vocabulary(Weighting.TF_IDF, Scoring.L1_NORM)
    bow, fv = voc.transform(np.zeros((0, 32), np.uint8))
    assert len(bow) == 0
    assert len(fv) == 0


def test_descriptor_validation() -> None:
    voc = _tiny_vocabulary(Weighting.TF_IDF, Scoring.L1_NORM)
    with pytest.raises(DataFormatError, match=r"expected shape \(N, 32\)"):
        voc.transform(np.zeros((3, 16), np.uint8))
    with pytest.raises(DataFormatError, match="expected uint8"):
        voc.transform(np.zeros((3, 32), np.float32))


def test_structure_validation() -> None:
    d = np.zeros((3, 32), np.uint8)
    with pytest.raises(DataFormatError, match="node 2 has parent 5"):
        Vocabulary(2, 1, 0, 0, [-1, 0, 5], d, np.zeros(3))
    with pytest.raises(DataFormatError, match="more than k=2"):
        Vocabulary(2, 1, 0, 0, [-1, 0, 0, 0], np.zeros((4, 32), np.uint8), np.zeros(4))
    with pytest.raises(DataFormatError, match="deeper than L=1"):
        Vocabulary(2, 1, 0, 0, [-1, 0, 1], d, np.zeros(3))
    with pytest.raises(ConfigurationError, match="k: expected"):
        Vocabulary(1, 1, 0, 0, [-1, 0], d[:2], np.zeros(2))


def test_training_builds_dbow2_tree_and_idf_weights() -> None:
    rng = np.random.default_rng(3)
    docs = [rng.integers(0, 256, (120, 32), dtype=np.uint8) for _ in range(6)]
    voc = Vocabulary.train(docs, k=4, L=3, rng=2, progress=False)
    assert voc.k == 4
    assert voc.L == 3
    # children of a node are contiguous and created after it (DBoW2's numbering)
    for node in range(voc.n_nodes):
        kids = np.flatnonzero(voc.parent == node)
        if kids.size:
            assert np.array_equal(kids, np.arange(kids[0], kids[0] + kids.size))
            assert kids[0] > node
    assert 0 < voc.n_words <= 4**3
    # idf = ln(N / N_i) recomputed by brute force
    ni = np.zeros(voc.n_words)
    for d in docs:
        ni[np.unique(voc.quantize(d)[0])] += 1
    w = voc.word_weights()
    assert w[ni > 0] == pytest.approx(np.log(6 / ni[ni > 0]))
    # each training descriptor's word is its nearest leaf along the greedy descent
    words, _, _ = voc.quantize(docs[0][:20])
    for f, word in zip(docs[0][:20], words, strict=True):
        node = 0
        while voc.child_count[node]:
            kids = np.flatnonzero(voc.parent == node)
            dist = [int(np.unpackbits(np.bitwise_xor(f, voc.descriptors[c])).sum()) for c in kids]
            node = int(kids[int(np.argmin(dist))])
        assert voc.word_of_node[node] == word


def test_training_is_reproducible_with_a_seed() -> None:
    rng = np.random.default_rng(4)
    docs = [rng.integers(0, 256, (80, 32), dtype=np.uint8) for _ in range(3)]
    a = Vocabulary.train(docs, k=3, L=2, rng=7, progress=False)
    b = Vocabulary.train(docs, k=3, L=2, rng=7, progress=False)
    assert a.equals(b)


def test_training_errors() -> None:
    with pytest.raises(ConfigurationError, match="at least one image"):
        Vocabulary.train([], progress=False)
    with pytest.raises(ConfigurationError, match="k: expected"):
        Vocabulary.train([np.zeros((3, 32), np.uint8)], k=1, progress=False)
    with pytest.raises(DataFormatError, match=r"training\[0\]"):
        Vocabulary.train([np.zeros((3, 31), np.uint8)], progress=False)


def test_train_from_folder(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import cv2
    import skimage.data

    for i, name in enumerate(("camera", "brick", "coins")):
        cv2.imwrite(str(tmp_path / f"img{i}.png"), getattr(skimage.data, name)())
    voc = Vocabulary.train_from_folder(tmp_path, k=5, L=2, rng=0, progress=False)
    assert voc.n_words > 5
    (tmp_path / "empty").mkdir()
    with pytest.raises(ConfigurationError, match="no images"):
        Vocabulary.train_from_folder(tmp_path / "empty")
    with pytest.raises(ConfigurationError, match="is not a directory"):
        Vocabulary.train_from_folder(tmp_path / "missing")


def test_same_image_scores_higher_than_other_images() -> None:
    trained_vocabulary = helpers.trained_vocabulary()
    extractor = helpers.extractor()
    wall_photos = helpers.wall_photos()
    bows = [trained_vocabulary.bow(extractor.extract(p).descriptors) for p in wall_photos]
    again = trained_vocabulary.bow(extractor.extract(wall_photos[0]).descriptors)
    scores = trained_vocabulary.score_many(again, bows)
    assert scores[0] == pytest.approx(1.0)
    assert np.all(scores[1:] < 0.5)
