"""Helpers every experiment shares: the common options, printing the configuration, JSON."""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["CARMEN_LOGS", "add_common_arguments", "find_carmen_dir", "print_config", "write_json"]

#: The real laser logs in ``../shared/data/carmen`` (see its README).
CARMEN_LOGS = ("intel", "aces", "freiburg-079")


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


def find_carmen_dir() -> Path | None:
    """``$SYMLOC_SHARED_DATA/carmen`` or ``<repo>/../shared/data/carmen``, if it exists."""
    env = os.environ.get("SYMLOC_SHARED_DATA")
    cands = [Path(env) / "carmen"] if env else []
    cands.append(Path(__file__).resolve().parents[3] / ".." / "shared" / "data" / "carmen")
    for c in cands:
        if c.is_dir():
            return c.resolve()
    return None
