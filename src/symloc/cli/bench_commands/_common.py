"""Options every ``symloc bench`` command shares: parallelism, outputs, seed."""

from __future__ import annotations

import argparse
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from symloc.bench.stats import json_safe
from symloc.bench.sweep import default_workers

__all__ = ["add_sweep_arguments", "write_json"]


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from err
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {value}")
    return value


def add_sweep_arguments(parser: argparse.ArgumentParser) -> None:
    """``--workers``, ``--ray``, ``--out`` and ``--json``."""
    parser.add_argument(
        "--workers",
        type=_positive_int,
        default=default_workers(),
        help=f"worker processes (default: all cores, here {default_workers()})",
    )
    parser.add_argument(
        "--ray",
        default=None,
        metavar="ADDRESS",
        help="run on Ray instead of local processes: 'local' (a private local instance), "
        "'auto' (a running cluster) or a cluster address; needs pip install 'symloc[ray]'",
    )
    parser.add_argument(
        "--out", type=Path, default=Path("symloc-bench"), metavar="DIR", help="output folder"
    )
    parser.add_argument(
        "--json", type=Path, default=None, metavar="PATH", help="also write the JSON here"
    )


def write_json(path: Path, data: Mapping[str, Any]) -> Path:
    """Write ``data`` as standard JSON (no NaN: None) to ``path``; returns ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(json_safe(dict(data)), indent=2, sort_keys=True) + "\n")
    return path
