"""``symloc experiment keyframes``: the paper's Figure 14, images stored over one full turn
(M = 4 per place against a keyframe every 5 degrees) and their bytes on disk."""

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
    """Add ``keyframes`` to ``symloc experiment``."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "keyframes", help="storage of M=4 images per place vs a keyframe every 5 deg (Figure 14)"
    )
    add_common_arguments(parser, "keyframes")
    parser.add_argument(
        "--m", type=options.directions, default=4, help="images per place (default 4)"
    )
    options.add_angle(parser, "--step-deg", default=5.0, help="keyframe step", dest="step")
    options.add_results(parser, "docs/results/keyframes.json")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symloc.bench.keyframes import run_keyframes
    from symloc.bench.provenance import RunClock

    config = {
        "seed": args.seed,
        "M": args.m,
        "keyframe step": f"{math.degrees(args.step):g} deg",
        "scene": "one full turn at the centre of a 3 m square in the textured lab, 640x480",
        "stored per image": "ORB keypoints + descriptors + BoW vector (+ PNG image)",
    }
    print_config("keyframes", config)
    clock = RunClock()
    results = run_keyframes(m=args.m, step_deg=math.degrees(args.step), rng=args.seed)
    print(
        f"\n{'policy':<26}{'images':>8}{'features':>10}{'bytes (features)':>18}{'bytes (+PNG)':>14}"
    )
    for r in results:
        print(
            f"{r.name:<26}{r.count:>8}{r.n_features:>10}{r.bytes_features:>18,}"
            f"{r.bytes_with_images:>14,}"
        )
    a, b = results[0], results[1]
    print(
        f"ratio: {b.count / a.count:.1f}x images, {b.bytes_features / a.bytes_features:.1f}x bytes "
        f"(features), {b.bytes_with_images / a.bytes_with_images:.1f}x bytes (with images)"
    )
    from symloc.figures.vision import keyframes_figure

    path = keyframes_figure(results, args.out / "keyframes.png")
    print(f"wrote {path}")
    write_json(args.json, {"seed": args.seed, "policies": [r.to_dict() for r in results]})
    policies = [{k: v for k, v in r.to_dict().items() if k != "angles_deg"} for r in results]
    write_results_file(args, clock, config, {"policies": policies})
    return 0
