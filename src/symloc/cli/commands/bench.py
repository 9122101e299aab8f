"""``symloc bench NAME``: the evaluation bench (sweeps over worlds, seeds and logs)."""

from __future__ import annotations

import argparse
from typing import Any

from symloc.cli.main import discover


def register(subparsers: Any) -> None:
    """Add ``bench`` with one sub-command per module of :mod:`symloc.cli.bench_commands`."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "bench",
        help="the evaluation bench: localization, symmetry or SLAM over many worlds and seeds",
    )
    sub = parser.add_subparsers(dest="bench", metavar="NAME")
    sub.required = True
    for module in discover("symloc.cli.bench_commands"):
        module.register(sub)
