"""``symloc experiment NAME``: the paper's tables and figures and our comparisons."""

from __future__ import annotations

import argparse
from typing import Any

from symloc.cli.main import discover


def register(subparsers: Any) -> None:
    """Add ``experiment`` with one sub-command per module of :mod:`symloc.experiments`."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "experiment", help="reproduce a table or figure of the paper, or one of ours"
    )
    sub = parser.add_subparsers(dest="experiment", metavar="NAME")
    sub.required = True
    for module in discover("symloc.experiments"):
        module.register(sub)
