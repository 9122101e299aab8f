"""Options every ``symloc bench`` command shares: parallelism, outputs, seed.

``--out``, ``--json`` and ``--seed`` come from :mod:`symloc.cli.options` (one vocabulary
across every command).
"""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from symloc.bench.sweep import default_workers
from symloc.cli import options

__all__ = ["add_sweep_arguments", "write_json"]


def add_sweep_arguments(parser: argparse.ArgumentParser, command: str = "bench") -> None:
    """``--workers``, ``--ray``, ``--out`` and ``--json``; ``command`` names the default output
    folder (``"bench localization"`` -> ``symloc-bench-localization``)."""
    parser.add_argument(
        "--workers",
        type=options.workers,
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
    options.add_out(parser, command)
    options.add_json(parser)


def write_json(path: Path, data: Mapping[str, Any]) -> Path:
    """Write ``data`` as standard JSON (no NaN: null) to ``path``; returns ``path``."""
    return options.write_json(path, data)
