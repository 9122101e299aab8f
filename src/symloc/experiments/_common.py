"""Helpers every experiment shares: the common options, printing the configuration, JSON."""

from __future__ import annotations

import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["add_common_arguments", "print_config", "write_json"]


def add_common_arguments(parser: Any, name: str) -> None:
    """Add ``--seed``, ``--json`` and ``--out`` (the folder for figures, default
    ``symloc-experiment-<name>``) to the parser of experiment ``name``
    (:mod:`symloc.cli.options`)."""
    options.add_seed(parser)
    options.add_json(parser)
    options.add_out(parser, f"experiment {name}", what="figures")


def print_config(name: str, config: Mapping[str, Any]) -> None:
    """Print an experiment's name, seed and configuration so a run can be reproduced."""
    print(f"# symloc experiment {name}")
    for key, value in config.items():
        print(f"#   {key}: {value}")
    sys.stdout.flush()


def write_json(path: Path | None, data: Mapping[str, Any]) -> None:
    """Write ``data`` as standard JSON (``null`` for NaN) to ``path``; no-op for None."""
    if path is None:
        return
    options.write_json(path, data)
    print(f"wrote {path}")
