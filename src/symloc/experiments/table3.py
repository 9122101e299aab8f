"""``symloc experiment table3``: the paper's Table 3 (BoW similarity of the 4 directions) and
the orientation decision at the centre of a square room, textured and untextured lab."""

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

PAPER_SIMILARITY = [
    [0.96, 0.12, 0.08, 0.10],
    [0.12, 0.93, 0.07, 0.08],
    [0.08, 0.07, 0.91, 0.13],
    [0.10, 0.08, 0.13, 0.95],
]


def register(subparsers: Any) -> None:
    """Add ``table3`` to ``symloc experiment``."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "table3", help="BoW similarity matrix and orientation decisions at a square's centre"
    )
    add_common_arguments(parser, "table3")
    options.add_trials(parser, default=50, what="trials per direction")
    parser.add_argument(
        "--side", type=options.room_side, default=3.0, help="square side [m] (paper: 3)"
    )
    parser.add_argument(
        "--radius-mm", type=options.positive_float, default=15.0, help="position spread [mm]"
    )
    options.add_angle(
        parser, "--heading-deg", default=5.0, help="largest heading error", dest="max_heading"
    )
    parser.add_argument("--vocabulary", default=None, help="vocabulary file (default: shipped)")
    options.add_results(parser, "docs/results/table3.json")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symloc.bench.provenance import RunClock
    from symloc.bench.table3 import run_table3
    from symloc.vision.vocabulary import Vocabulary

    voc = Vocabulary.load(args.vocabulary) if args.vocabulary else None
    config = {
        "seed": args.seed,
        "trials per direction": args.trials,
        "room": f"square {args.side:g} m inside a 12-segment lab (textured, then untextured)",
        "robot spread": f"uniform in a {args.radius_mm:g} mm disc, heading +-{math.degrees(args.max_heading):g} deg",
        "vocabulary": args.vocabulary or "shipped default (k=10, L=5, TF-IDF, L1)",
    }
    print_config("table3", config)
    clock = RunClock()
    res = run_table3(
        trials=args.trials,
        side=args.side,
        radius=args.radius_mm / 1000.0,
        max_heading_error=args.max_heading,
        vocabulary=voc,
        rng=args.seed,
    )
    d = res.to_dict()
    print("\nmean BoW similarity (DBoW2 L1 score), query direction (row) x stored image (col)")
    print("          " + "".join(f"{'image ' + str(i + 1):>10}" for i in range(4)))
    for j, row in enumerate(d["similarity"]):
        ours = "".join(f"{v:>10.3f}" for v in row)
        paper = " ".join(f"{v:.2f}" for v in PAPER_SIMILARITY[j])
        print(f"image {j + 1:<3} {ours}    paper: {paper}")
    c = d["counts"]
    print(
        f"\ntextured lab:   accuracy {100 * d['accuracy']:.1f} % ({c['correct']}/{c['trials']}), "
        f"wrong {c['wrong']}, undetermined {c['undetermined']} (refused {c['refused']})"
    )
    print(
        f"with the retry protocol (turn 90 deg clockwise, up to 4 images): accuracy "
        f"{100 * d['accuracy_with_retries']:.1f} %, wrong {c['wrong_after_retries']} "
        f"({c['retried']} trials retried)"
    )
    print(
        f"heading error after offset correction: median {d['heading_error_deg_median']:.3f} deg, "
        f"95th pct {d['heading_error_deg_p95']:.3f} deg, max {d['heading_error_deg_max']:.3f} deg "
        f"(uncorrected, i.e. k x 90 deg only: median {d['heading_error_uncorrected_deg_median']:.3f} deg)"
    )
    r = d["score_ratio_best_to_second"]
    print(
        f"best/second BoW score ratio over the textured trials: min {r['min']:.2f}, "
        f"median {r['median']:.2f} (the decision needs >= 2)"
    )
    u = d["untextured"]
    print(
        f"untextured lab: undetermined {u['undetermined']}/{u['trials']} "
        f"(refused {u['refused']}), wrong {u['wrong']}, correct {u['correct']}; after retries: "
        f"wrong {u['wrong_after_retries']}, correct {u['correct_after_retries']}"
    )
    us = d["untextured_sensitive_orb"]
    if us["trials"]:
        print(
            f"untextured lab, ORB FAST threshold {us['fast_threshold']} "
            f"({us['mean_keypoints']:.0f} keypoints per image from board edges and noise): "
            f"undetermined {us['undetermined']}/{us['trials']} (refused {us['refused']}), "
            f"wrong {us['wrong']}, correct {us['correct']}; after retries: "
            f"wrong {us['wrong_after_retries']}, correct {us['correct_after_retries']}"
        )
    from symloc.figures.vision import matches_figure, table3_figure

    path = table3_figure(res, args.out / "table3.png")
    print(f"wrote {path}")
    if res.example_query is not None and res.stored_images:
        path = matches_figure(res.example_query, res.stored_images, args.out / "table3_matches.png")
        print(f"wrote {path} (the paper's Figure 13)")
    write_json(args.json, {"seed": args.seed, "paper_similarity": PAPER_SIMILARITY, **d})
    write_results_file(args, clock, config, {"paper_similarity": PAPER_SIMILARITY, **d})
    return 0
