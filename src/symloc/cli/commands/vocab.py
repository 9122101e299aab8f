"""``symloc vocab``: train a vocabulary from a folder of images, convert between DBoW2 text and
symloc's binary format, and describe a vocabulary file."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["register"]

_WEIGHTINGS = ["tf-idf", "tf", "idf", "binary"]
_SCORINGS = ["l1", "l2", "chi-square", "kl", "bhattacharyya", "dot-product"]


def register(subparsers: Any) -> None:
    """Add ``vocab`` with ``train``, ``convert`` and ``info``."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "vocab", help="visual vocabularies (DBoW2-compatible): train, convert, info"
    )
    sub = parser.add_subparsers(dest="vocab_command", metavar="ACTION")
    sub.required = True

    t = sub.add_parser(
        "train",
        help="train a vocabulary on the ORB features of every image in a folder",
        description="Hierarchical k-means of ORB descriptors (DBoW2's scheme: k-means++ seeding, "
        "bit-wise majority centres, Hamming distance), then word weights. Images are searched "
        "recursively (png, jpg, bmp, tif, pgm, ppm); unreadable files and images too small for ORB (a side under 63 px) are skipped, counted in a warning.",
    )
    t.add_argument("folder", type=Path, help="folder of training images")
    t.add_argument(
        "--k", type=options.vocabulary_k, default=10, help="branching factor (default 10)"
    )
    t.add_argument(
        "--L", type=options.vocabulary_levels, default=5, help="depth levels (default 5)"
    )
    t.add_argument(
        "--weighting", choices=_WEIGHTINGS, default="tf-idf", help="word weights (tf-idf)"
    )
    t.add_argument("--scoring", choices=_SCORINGS, default="l1", help="BoW scoring (l1)")
    t.add_argument(
        "--features",
        type=options.orb_features,
        default=1000,
        help="ORB features per image (default 1000)",
    )
    options.add_out(t, "vocab train", what="vocabulary.symvoc (or vocabulary.txt)")
    t.add_argument(
        "--format",
        choices=("symloc", "dbow2"),
        default="symloc",
        help="symloc binary (vocabulary.symvoc, default) or DBoW2 text (vocabulary.txt)",
    )
    t.add_argument("--compress", action="store_true", help="zlib-compress the binary output")
    options.add_seed(t)
    t.set_defaults(func=_train)

    c = sub.add_parser(
        "convert",
        help="convert DBoW2 text (ORBvoc.txt, .txt.gz) <-> symloc binary",
        description="OUT ending in .txt gets DBoW2's text format (loadFromTextFile), anything "
        "else symloc's binary format. The input format is detected from its content.",
    )
    c.add_argument("input", type=Path, help="vocabulary file to read")
    c.add_argument("output", type=options.output_file, help="file to write (.txt: DBoW2 text)")
    c.add_argument("--compress", action="store_true", help="zlib-compress the binary output")
    c.set_defaults(func=_convert)

    i = sub.add_parser("info", help="k, L, words, weighting, scoring and size of a vocabulary")
    i.add_argument("path", type=Path, help="vocabulary file")
    i.set_defaults(func=_info)


def _save(voc: Any, out: Path, compress: bool) -> None:
    from symloc.errors import ConfigurationError
    from symloc.vision.vocabulary import save_dbow2_text, save_vocabulary

    if not out.parent.is_dir():
        raise ConfigurationError(f"{out}: folder {out.parent} does not exist")
    if out.suffix == ".txt":
        save_dbow2_text(voc, out)
    else:
        save_vocabulary(voc, out, compress=compress)


def _train(args: argparse.Namespace) -> int:
    from symloc.vision.orb import OrbExtractor, OrbSettings
    from symloc.vision.vocabulary import Vocabulary

    weighting = args.weighting
    scoring = args.scoring.replace("dot-product", "dot_product")
    print(
        f"# symloc vocab train {args.folder}: seed {args.seed}, k={args.k}, L={args.L}, "
        f"weighting {args.weighting}, scoring {args.scoring}, {args.features} ORB features/image"
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        voc = Vocabulary.train_from_folder(
            args.folder,
            extractor=OrbExtractor(OrbSettings(n_features=args.features)),
            k=args.k,
            L=args.L,
            weighting=weighting,
            scoring=scoring,
            rng=args.seed,
            progress=True,
        )
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    out = Path(args.out) / ("vocabulary.txt" if args.format == "dbow2" else "vocabulary.symvoc")
    out.parent.mkdir(parents=True, exist_ok=True)
    _save(voc, out, args.compress)
    print(f"{voc!r} -> {out} ({out.stat().st_size:,} bytes)")
    return 0


def _convert(args: argparse.Namespace) -> int:
    from symloc.vision.vocabulary import load_vocabulary

    options.refuse_overwriting_inputs({"input": args.input}, {"output": args.output})
    voc = load_vocabulary(args.input)
    _save(voc, args.output, args.compress)
    print(f"{voc!r}: {args.input} -> {args.output} ({args.output.stat().st_size:,} bytes)")
    return 0


def _info(args: argparse.Namespace) -> int:
    from symloc.vision.vocabulary import load_vocabulary
    from symloc.vision.vocabulary_io import MAGIC

    voc = load_vocabulary(args.path)
    with open(args.path, "rb") as fh:
        head = fh.read(len(MAGIC) + 36)
    if head[: len(MAGIC)] == MAGIC:
        flags = int.from_bytes(head[40:44], "little")
        fmt = "symloc binary" + (" (compressed)" if flags & 1 else "")
    else:
        fmt = "DBoW2 text"
    print(f"file:      {args.path}")
    print(f"format:    {fmt}")
    print(f"k:         {voc.k}")
    print(f"L:         {voc.L}")
    print(f"words:     {voc.n_words:,}")
    print(f"nodes:     {voc.n_nodes:,}")
    print(f"weighting: {voc.weighting.name}")
    print(f"scoring:   {voc.scoring.name}")
    print(f"size:      {args.path.stat().st_size:,} bytes")
    return 0
