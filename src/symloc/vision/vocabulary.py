"""A DBoW2-compatible visual vocabulary: a tree of binary words, weights, transform and score.

The tree is held as flat NumPy arrays (no per-node Python objects): ``parent``, the node
descriptors and weights, and a children index built from ``parent``. :meth:`Vocabulary.transform`
quantises all features of an image level by level at once (XOR + ``np.bitwise_count``), and
builds the BoW vector and the direct index exactly as DBoW2's ``TemplatedVocabulary::transform``
does, including its quirks (TF divides by the number of distinct words when the scoring does
not normalise; words with weight 0 are stop words and are dropped).
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import as_rng
from symloc.errors import ConfigurationError, DataFormatError, VocabularyFileError
from symloc.image_header import read_image_file
from symloc.vision.bow import (
    BowMatrix,
    BowVector,
    FeatureVector,
    Scoring,
    Weighting,
    normalization_of,
    normalize_values,
    parse_scoring,
    parse_weighting,
    score_many,
)
from symloc.vision.hkmeans import as_u64, hierarchical_kmeans
from symloc.vision.tree_descent import bow_parts, descend
from symloc.vision.vocabulary_io import (
    VocabularyArrays,
    read_dbow2_text,
    read_vocabulary,
    write_dbow2_text,
    write_vocabulary,
)

if TYPE_CHECKING:
    from symloc.vision.orb import OrbExtractor

__all__ = [
    "Vocabulary",
    "check_descriptors",
    "load_dbow2_text",
    "load_vocabulary",
    "save_dbow2_text",
    "save_vocabulary",
]

_log = logging.getLogger(__name__)

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm")


def check_descriptors(descriptors: ArrayLike, name: str = "descriptors") -> NDArray[np.uint8]:
    """Return ``(N, 32)`` contiguous uint8 ORB descriptors or raise naming ``name``."""
    d = np.asarray(descriptors)
    if d.dtype != np.uint8:
        raise DataFormatError(f"{name}: expected uint8 binary descriptors, got dtype {d.dtype}")
    if d.ndim == 1 and d.size == 0:
        d = d.reshape(0, 32)
    if d.ndim != 2 or d.shape[1] != 32:
        raise DataFormatError(f"{name}: expected shape (N, 32), got {d.shape}")
    return np.ascontiguousarray(d)


class Vocabulary:
    """A hierarchical vocabulary of binary words (DBoW2's ``TemplatedVocabulary<FORB>``).

    Parameters
    ----------
    k : int
        Branching factor (DBoW2 allows 2..20 in its files).
    L : int
        Depth levels (1..10).
    weighting, scoring : Weighting, Scoring (or their names / DBoW2 codes)
    parent : (N,) int array
        Parent of each node; node 0 is the root (its parent is ignored).
    descriptors : (N, 32) uint8
        Node descriptors (the root's is ignored).
    weights : (N,) float
        Node weights (meaningful for leaves, i.e. words).

    Notes
    -----
    Words are the leaves, numbered in node order (DBoW2's ``createWords``).
    """

    def __init__(
        self,
        k: int,
        L: int,
        weighting: Weighting | int | str,
        scoring: Scoring | int | str,
        parent: ArrayLike,
        descriptors: ArrayLike,
        weights: ArrayLike,
    ) -> None:
        if int(k) != k or not 2 <= k <= 255:
            raise ConfigurationError(f"k: expected an integer branching factor >= 2, got {k}")
        if int(L) != L or not 1 <= L <= 32:
            raise ConfigurationError(f"L: expected an integer depth >= 1, got {L}")
        self.k = int(k)
        self.L = int(L)
        self.weighting = parse_weighting(weighting)
        self.scoring = parse_scoring(scoring)
        par = np.ascontiguousarray(parent, dtype=np.int32).reshape(-1)
        desc = check_descriptors(descriptors, "descriptors")
        w = np.ascontiguousarray(weights, dtype=np.float64).reshape(-1)
        n = par.size
        if n < 1 or desc.shape[0] != n or w.size != n:
            raise DataFormatError(
                f"vocabulary: parent ({n}), descriptors ({desc.shape[0]}) and weights ({w.size}) "
                "must have the same number (>= 1) of nodes"
            )
        par = par.copy()
        par[0] = -1
        bad = np.flatnonzero((par[1:] < 0) | (par[1:] >= np.arange(1, n)))
        if bad.size:
            i = int(bad[0]) + 1
            raise DataFormatError(
                f"vocabulary: node {i} has parent {int(par[i])}; expected an earlier node"
            )
        if not np.all(np.isfinite(w)):
            raise DataFormatError("vocabulary: weights contain NaN or infinite values")
        self.parent = par
        self.descriptors = desc
        self.weights = w
        self._build_index()

    # ------------------------------------------------------------------ structure
    def _build_index(self) -> None:
        n = self.parent.size
        child_count = np.bincount(self.parent[1:], minlength=n).astype(np.int32)
        if child_count.max(initial=0) > self.k:
            node = int(np.argmax(child_count))
            raise DataFormatError(
                f"vocabulary: node {node} has {int(child_count[node])} children, more than k={self.k}"
            )
        self.child_ids = (np.argsort(self.parent[1:], kind="stable") + 1).astype(np.int32)
        self.child_start = np.concatenate([[0], np.cumsum(child_count)[:-1]]).astype(np.int64)
        self.child_count = child_count
        is_leaf = child_count == 0
        is_leaf[0] = False
        self.is_leaf = is_leaf
        self.word_nodes = np.flatnonzero(is_leaf).astype(np.int32)
        self.word_of_node = np.full(n, -1, np.int32)
        self.word_of_node[self.word_nodes] = np.arange(self.word_nodes.size, dtype=np.int32)
        self._desc64 = as_u64(self.descriptors)
        self._descent: tuple[NDArray[Any], ...] | None = None
        depth = np.zeros(n, np.int32)
        # parents precede children, so one vectorised pass per level fixes the depths
        for _ in range(self.L + 1):
            depth[1:] = depth[self.parent[1:]] + 1
        self.depth = depth
        if n > 1 and int(depth.max()) > self.L:
            node = int(np.argmax(depth))
            raise DataFormatError(
                f"vocabulary: node {node} is at depth {int(depth[node])}, deeper than L={self.L}"
            )

    def _descent_index(self) -> tuple[NDArray[Any], ...]:
        """Per inner node, its children's ids and descriptors in one ``(I, k)`` / ``(I, k, 4)``
        block, so that one level of the descent is a single gather + XOR + popcount for all
        features. Built on first use (not at load time)."""
        if self._descent is None:
            n = self.n_nodes
            internal = np.flatnonzero(self.child_count > 0)
            row_of = np.full(n, -1, np.int64)
            row_of[internal] = np.arange(internal.size)
            kk = np.arange(self.k)
            slots = self.child_start[internal][:, None] + kk[None, :]
            valid = kk[None, :] < self.child_count[internal][:, None]
            safe = np.minimum(slots, max(self.child_ids.size - 1, 0))
            kid_ids = (
                self.child_ids[safe] if self.child_ids.size else np.zeros(slots.shape, np.int32)
            )
            kid_ids = np.where(valid, kid_ids, 0).astype(np.int32)
            # missing children (fewer than k) get a penalty larger than any Hamming distance
            penalty = np.where(valid, 0, 1 << 16).astype(np.int32)
            self._descent = (row_of, kid_ids, self._desc64[kid_ids], penalty)
        return self._descent

    @property
    def n_nodes(self) -> int:
        """Number of nodes including the root."""
        return int(self.parent.size)

    @property
    def n_words(self) -> int:
        """Number of words (leaves)."""
        return int(self.word_nodes.size)

    def __len__(self) -> int:
        return self.n_words

    def fingerprint(self) -> str:
        """``sha256:<hex>`` of the tree, words and weights: the identity of the BoW space.

        Two vocabularies with the same fingerprint make the same BoW vectors; a visual map
        stores its vocabulary's fingerprint so a query with another one is refused.
        """
        import hashlib

        h = hashlib.sha256()
        h.update(f"{self.k} {self.L} {int(self.weighting)} {int(self.scoring)}".encode())
        for a in (self.parent.astype("<i4"), self.descriptors, self.weights.astype("<f8")):
            h.update(np.ascontiguousarray(a).tobytes())
        return "sha256:" + h.hexdigest()

    def __repr__(self) -> str:
        return (
            f"Vocabulary(k={self.k}, L={self.L}, weighting={self.weighting.name}, "
            f"scoring={self.scoring.name}, words={self.n_words})"
        )

    def word_weights(self) -> NDArray[np.float64]:
        """``(W,)`` weight of each word (idf for TF_IDF/IDF, 1 for TF/BINARY)."""
        return self.weights[self.word_nodes]

    # ------------------------------------------------------------------ quantisation
    def quantize(
        self, descriptors: ArrayLike, levelsup: int = 0
    ) -> tuple[NDArray[np.int32], NDArray[np.float64], NDArray[np.int32]]:
        """Descend the tree with every descriptor (DBoW2's per-feature ``transform``).

        Parameters
        ----------
        descriptors : (N, 32) uint8
        levelsup : int
            The direct-index node is the ancestor at level ``L - levelsup`` (0: the word's node).

        Returns
        -------
        word_ids : (N,) int32
        weights : (N,) float64
        direct_nodes : (N,) int32
            Node at level ``L - levelsup`` (the root when that level is <= 0; the leaf when the
            leaf is shallower than that level).
        """
        desc = check_descriptors(descriptors)
        n = desc.shape[0]
        cur = np.zeros(n, np.int32)
        nid = np.zeros(n, np.int32)
        nid_level = self.L - int(levelsup)
        if self.n_nodes == 1 or n == 0:
            return np.full(n, -1, np.int32), np.zeros(n), nid
        row_of, kid_ids, kid_desc64, _penalty = self._descent_index()
        descend(as_u64(desc), row_of, kid_ids, kid_desc64, self.child_count, nid_level, cur, nid)
        word_ids = self.word_of_node[cur]
        return word_ids, self.weights[cur], nid

    def transform(
        self, descriptors: ArrayLike, levelsup: int = 0
    ) -> tuple[BowVector, FeatureVector]:
        """Convert an image's descriptors to a BoW vector and a direct index (DBoW2 semantics).

        Parameters
        ----------
        descriptors : (N, 32) uint8
            ORB descriptors of one image.
        levelsup : int
            Levels up from the leaves for the direct index (ORB-SLAM uses 4).

        Returns
        -------
        bow : BowVector
            Normalised as :attr:`scoring` requires.
        direct : FeatureVector
            Node -> indices of the features that passed through it.
        """
        return self._bow_and_direct(*self.quantize(descriptors, levelsup))

    def _bow_and_direct(
        self, words: NDArray[np.int32], w: NDArray[np.float64], nid: NDArray[np.int32]
    ) -> tuple[BowVector, FeatureVector]:
        """The BoW vector and direct index of quantised features (:meth:`quantize`'s output,
        ``(N,)`` each): stop words (weight 0) dropped, weights summed (TF, TF-IDF) or taken
        once (IDF, binary) per word, then normalised as :attr:`scoring` requires."""
        sum_weights = self.weighting in (Weighting.TF, Weighting.TF_IDF)
        uniq, values, nodes, indptr, indices = bow_parts(words, w, nid, sum_weights)
        norm = normalization_of(self.scoring)
        if norm is None:
            if sum_weights and uniq.size:
                values = values / float(uniq.size)
        else:
            values = normalize_values(values, norm)
        return BowVector(uniq, values), FeatureVector(nodes, indptr, indices)

    def bow(self, descriptors: ArrayLike) -> BowVector:
        """Only the BoW vector of :meth:`transform`."""
        return self.transform(descriptors)[0]

    def score(self, a: BowVector, b: BowVector) -> float:
        """DBoW2 score of two BoW vectors with this vocabulary's scoring."""
        return float(score_many(a, BowMatrix.stack([b]), self.scoring)[0])

    def score_many(
        self, query: BowVector, database: BowMatrix | Sequence[BowVector]
    ) -> NDArray[np.float64]:
        """Scores ``(n,)`` of ``query`` against each database vector."""
        return score_many(query, database, self.scoring)

    # ------------------------------------------------------------------ training
    @classmethod
    def train(
        cls,
        training: Sequence[ArrayLike],
        *,
        k: int = 10,
        L: int = 5,
        weighting: Weighting | int | str = Weighting.TF_IDF,
        scoring: Scoring | int | str = Scoring.L1_NORM,
        rng: np.random.Generator | int | None = None,
        max_iterations: int | None = 100,
        progress: bool = True,
    ) -> Vocabulary:
        """Build a vocabulary with DBoW2's ``create`` (hierarchical k-means, then weights).

        Parameters
        ----------
        training : sequence of (n_i, 32) uint8
            Descriptors of each training image (the images count as documents for the idf).
        k, L : int
            Branching factor and depth levels.
        weighting, scoring : DBoW2 types or names
        rng : Generator, int or None
        max_iterations : int or None
            Lloyd iterations per node (None: until convergence, as DBoW2).
        progress : bool
            Show a tqdm bar (stderr) of descriptors clustered.

        Returns
        -------
        Vocabulary
        """
        if int(k) != k or k < 2:
            raise ConfigurationError(f"k: expected an integer >= 2, got {k}")
        if int(L) != L or L < 1:
            raise ConfigurationError(f"L: expected an integer >= 1, got {L}")
        docs = [check_descriptors(d, f"training[{i}]") for i, d in enumerate(training)]
        if not docs or sum(d.shape[0] for d in docs) == 0:
            raise ConfigurationError("training: expected at least one image with descriptors")
        gen = as_rng(rng)
        allc = np.concatenate(docs)
        from tqdm import tqdm

        with tqdm(
            total=allc.shape[0] * L, desc="hierarchical k-means", unit="desc", disable=not progress
        ) as bar:
            tree = hierarchical_kmeans(
                allc, int(k), int(L), gen, max_iterations=max_iterations, on_node=bar.update
            )
        voc = cls(
            k, L, weighting, scoring, tree.parent, tree.descriptors, np.zeros(tree.parent.size)
        )
        voc._set_node_weights(docs)
        return voc

    def _set_node_weights(self, docs: Sequence[NDArray[np.uint8]]) -> None:
        """DBoW2's ``setNodeWeights``: 1 for TF/BINARY, ``ln(N / N_i)`` for IDF/TF_IDF."""
        weights = np.zeros(self.n_nodes)
        if self.weighting in (Weighting.TF, Weighting.BINARY):
            weights[self.word_nodes] = 1.0
        else:
            ni = np.zeros(self.n_words, np.int64)
            for d in docs:
                words = self.quantize(d)[0]
                ni[np.unique(words[words >= 0])] += 1
            ok = ni > 0
            weights[self.word_nodes[ok]] = np.log(len(docs) / ni[ok])
        self.weights = weights

    @classmethod
    def train_from_folder(
        cls,
        folder: str | Path,
        *,
        extractor: OrbExtractor | None = None,
        recursive: bool = True,
        progress: bool = True,
        **kwargs: Any,
    ) -> Vocabulary:
        """Extract ORB features from every image in ``folder`` and :meth:`train` on them.

        ``kwargs`` go to :meth:`train` (k, L, weighting, scoring, rng, max_iterations).
        """
        import cv2
        from tqdm import tqdm

        from symloc.vision.orb import OrbExtractor  # lazy, like cv2 above: only to train on files

        root = Path(folder)
        if not root.is_dir():
            raise ConfigurationError(f"folder: {root} is not a directory")
        files = sorted(
            p
            for p in (root.rglob("*") if recursive else root.iterdir())
            if p.suffix.lower() in IMAGE_SUFFIXES
        )
        if not files:
            raise ConfigurationError(f"folder: no images ({', '.join(IMAGE_SUFFIXES)}) in {root}")
        ext = extractor or OrbExtractor()
        docs = []
        unreadable = []
        too_small = []
        side = ext.min_image_side
        for p in tqdm(files, desc="ORB features", unit="img", disable=not progress):
            try:
                img = read_image_file(p, flags=cv2.IMREAD_GRAYSCALE)
            except DataFormatError:
                unreadable.append(p)
                continue
            if min(img.shape[:2]) < side:
                too_small.append(p)
                continue
            d = ext.extract(img).descriptors
            if d.shape[0]:
                docs.append(d)
        import warnings

        if unreadable:
            warnings.warn(
                f"folder: skipped {len(unreadable)} unreadable image file(s), e.g. {unreadable[0]}",
                stacklevel=2,
            )
        if too_small:
            warnings.warn(
                f"folder: skipped {len(too_small)} image(s) smaller than {side} x {side} pixels"
                f" (ORB finds no keypoint in them), e.g. {too_small[0]}",
                stacklevel=2,
            )
        if not docs:
            raise DataFormatError(
                f"folder: none of the {len(files)} image file(s) in {root} is a readable image "
                "with ORB features"
            )
        return cls.train(docs, progress=progress, **kwargs)

    # ------------------------------------------------------------------ files
    @classmethod
    def from_arrays(cls, arrays: VocabularyArrays) -> Vocabulary:
        """The vocabulary of a tree read from a file, checked; a bad tree raises
        :class:`~symloc.errors.VocabularyFileError` naming the file and where the tree starts."""
        a = arrays
        try:
            w, s = Weighting(a.weighting), Scoring(a.scoring)
            return cls(a.k, a.L, w, s, a.parent, a.descriptors, a.weights)
        except ValueError as err:
            raise VocabularyFileError(f"{a.source}: {a.where}: {err}") from err

    def save(self, path: str | Path, *, compress: bool = False) -> None:
        """Write the native binary format (see :mod:`symloc.vision.vocabulary_io`)."""
        write_vocabulary(self, path, compress=compress)

    @classmethod
    def load(cls, path: str | Path) -> Vocabulary:
        """Read the native binary format (or a DBoW2 text file, by its content)."""
        return cls.from_arrays(read_vocabulary(path))

    @classmethod
    def load_dbow2_text(cls, path: str | Path) -> Vocabulary:
        """Read a DBoW2 text vocabulary (ORB-SLAM's ORBvoc.txt layout)."""
        return cls.from_arrays(read_dbow2_text(path))

    def save_dbow2_text(self, path: str | Path) -> None:
        """Write a DBoW2 text vocabulary (readable by DBoW2 ``loadFromTextFile``)."""
        write_dbow2_text(self, path)

    def equals(self, other: Vocabulary, *, weight_rtol: float = 0.0) -> bool:
        """True if both vocabularies have the same structure, words and (close) weights."""
        return (
            self.k == other.k
            and self.L == other.L
            and self.weighting == other.weighting
            and self.scoring == other.scoring
            and np.array_equal(self.parent, other.parent)
            and np.array_equal(self.descriptors[1:], other.descriptors[1:])
            and np.allclose(self.weights[1:], other.weights[1:], rtol=weight_rtol, atol=0.0)
        )


def save_vocabulary(voc: Vocabulary, path: str | Path, *, compress: bool = False) -> None:
    """Write ``voc`` in the native binary format (``compress``: zlib level 6 on weights and
    parents, descriptors raw; see :mod:`symloc.vision.vocabulary_io`)."""
    voc.save(path, compress=compress)


def load_vocabulary(path: str | Path) -> Vocabulary:
    """Load a vocabulary file: native binary, or DBoW2 text (detected by content).

    Raises
    ------
    VocabularyFileError
        The file is corrupt or truncated; the message names the byte (binary) or line (text).
    """
    return Vocabulary.load(path)


def load_dbow2_text(path: str | Path) -> Vocabulary:
    """Read a DBoW2 text vocabulary (``ORBvoc.txt``; ``.gz`` accepted).

    Raises
    ------
    VocabularyFileError
        Naming the line (1-based) that is malformed.
    """
    return Vocabulary.load_dbow2_text(path)


def save_dbow2_text(voc: Vocabulary, path: str | Path) -> None:
    """Write ``voc`` as a DBoW2 text vocabulary (``saveToTextFile`` layout, full precision)."""
    voc.save_dbow2_text(path)


def main(argv: list[str] | None = None) -> int:
    """``python -m symloc.vision.vocabulary IN OUT``: convert between the two formats.

    An OUT ending in ``.txt`` gets DBoW2 text, anything else the native binary format
    (``--compress`` for zlib). Importing ORB-SLAM's ORBvoc.txt once this way makes later loads
    take a fraction of a second instead of seconds.
    """
    import argparse

    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stdout)
    ap = argparse.ArgumentParser(description="Convert a vocabulary (DBoW2 text <-> symloc binary).")
    ap.add_argument("input", type=Path)
    ap.add_argument("output", type=Path)
    ap.add_argument("--compress", action="store_true", help="zlib-compress the binary output")
    args = ap.parse_args(argv)
    voc = load_vocabulary(args.input)
    if args.output.suffix == ".txt":
        save_dbow2_text(voc, args.output)
    else:
        save_vocabulary(voc, args.output, compress=args.compress)
    _log.info("%r -> %s (%d bytes)", voc, args.output, args.output.stat().st_size)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
