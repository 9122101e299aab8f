"""``symloc experiment photos``: the orientation decision on real photographs (re-captured with
a camera yaw, scale, exposure, JPEG, noise and occlusion), and ambiguous places that must stay
undetermined (duplicate, near-duplicate, mirrored and featureless directions)."""

from __future__ import annotations

import argparse
import math
from typing import Any

from symloc.cli import options
from symloc.experiments._common import (
    add_common_arguments,
    print_config,
    write_json,
    write_results_file,
)

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    """Add ``photos`` to ``symloc experiment``."""
    from symloc.bench.photos import CONDITIONS, PLACE_PHOTOS

    parser: argparse.ArgumentParser = subparsers.add_parser(
        "photos",
        help="orientation decisions on real photos (re-captures, near-duplicates, featureless)",
    )
    add_common_arguments(parser, "photos")
    options.add_trials(parser, default=25, what="queries per direction and case")
    options.add_angle(parser, "--max-yaw", default=5.0, help="largest camera yaw")
    parser.add_argument(
        "--photos",
        nargs=4,
        default=list(PLACE_PHOTOS),
        metavar="NAME",
        help="four skimage.data photos as the four directions",
    )
    parser.add_argument(
        "--conditions",
        nargs="+",
        default=list(CONDITIONS),
        choices=CONDITIONS,
        metavar="COND",
        help=f"re-capture conditions (default all: {', '.join(CONDITIONS)})",
    )
    parser.add_argument("--vocabulary", default=None, help="vocabulary file (default: shipped)")
    parser.add_argument(
        "--bow-only",
        action="store_true",
        help="the paper's BoW-first rule: no geometric fallback when BoW is ambiguous",
    )
    parser.add_argument(
        "--offset-from",
        choices=["rotation", "homography"],
        default="rotation",
        help="heading offset from a rotation+zoom fit to the inliers (default) or from the "
        "8-DOF homography",
    )
    options.add_results(parser, "docs/results/photos.json")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symloc.bench.photos import example_views, run_photos
    from symloc.vision.default_vocabulary import default_vocabulary
    from symloc.vision.orientation import OrientationConfig
    from symloc.vision.vocabulary import Vocabulary

    voc = Vocabulary.load(args.vocabulary) if args.vocabulary else default_vocabulary()
    cfg = OrientationConfig(geometric_fallback=not args.bow_only, offset_from=args.offset_from)
    config = {
        "seed": args.seed,
        "photos (directions 1..4)": ", ".join(args.photos),
        "vocabulary": args.vocabulary or "shipped default (not trained on these photos)",
        "camera": "640x480, f=500 px (hfov 65.2 deg)",
        "trials per direction and case": args.trials,
        "max yaw": f"{math.degrees(args.max_yaw):g} deg",
        "conditions": ", ".join(args.conditions),
        "decision": "BoW first, no geometric fallback" if args.bow_only else "BoW + geometry",
        "heading offset from": args.offset_from,
    }
    print_config("photos", config)
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    res = run_photos(
        voc,
        photos=args.photos,
        trials_per_direction=args.trials,
        max_yaw_deg=math.degrees(args.max_yaw),
        conditions=args.conditions,
        config=cfg,
        rng=args.seed,
    )
    head = (
        f"{'case':<16}{'trials':>7}{'correct':>8}{'wrong':>6}{'undet.':>7}{'refused':>8}"
        f"{'acc.':>7}  heading err [deg] med / p95 / max"
    )

    def line(c: Any) -> str:
        err = (
            f"{c.heading_error_deg_median:.2f} / {c.heading_error_deg_p95:.2f} / "
            f"{c.heading_error_deg_max:.2f}"
            if not math.isnan(c.heading_error_deg_median)
            else "-"
        )
        return (
            f"{c.case:<16}{c.trials:>7}{c.correct:>8}{c.wrong:>6}{c.undetermined:>7}"
            f"{c.refused:>8}{100 * c.accuracy:>6.1f}%  {err}"
        )

    print("\nre-captures of the 4 directions (each with a random yaw):")
    print(head)
    for c in res.conditions:
        print(line(c))
    print("\nambiguous places (queries re-captured with all perturbations; featureless: yaw only):")
    print(head + "   with retries: correct / wrong")
    for c in res.ambiguity:
        print(f"{line(c)}   {c.retry_correct} / {c.retry_wrong}")
        print(f"{'':<16}({c.note})")
    from symloc.figures.vision import photos_figure

    path = photos_figure(
        res,
        args.out / "photos.png",
        example_views(args.photos, args.seed, math.degrees(args.max_yaw)),
    )
    print(f"wrote {path}")
    write_json(
        args.json,
        {
            "seed": args.seed,
            "bow_only": args.bow_only,
            "offset_from": args.offset_from,
            **res.to_dict(),
        },
    )
    write_results_file(args, clock, config, res.to_dict())
    return 0
