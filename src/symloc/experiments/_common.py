"""Helpers every experiment shares: printing the configuration, writing JSON."""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["CARMEN_LOGS", "add_common_arguments", "find_carmen_dir", "print_config", "write_json"]

#: The real laser logs in ``../shared/data/carmen`` (see its README).
CARMEN_LOGS = ("intel", "aces", "freiburg-079")


def add_common_arguments(parser: Any, *, default_seed: int = 0) -> None:
    """Add ``--seed``, ``--json`` and ``--out`` (figure directory) to an experiment parser."""
    parser.add_argument("--seed", type=int, default=default_seed, help="random seed (printed)")
    parser.add_argument("--json", type=Path, default=None, metavar="PATH", help="write results")
    parser.add_argument(
        "--out", type=Path, default=Path("."), metavar="DIR", help="directory for figures"
    )


def print_config(name: str, config: Mapping[str, Any]) -> None:
    """Print an experiment's name, seed and configuration so a run can be reproduced."""
    print(f"# symloc experiment {name}")
    for key, value in config.items():
        print(f"#   {key}: {value}")
    sys.stdout.flush()


def write_json(path: Path | None, data: Mapping[str, Any]) -> None:
    """Write ``data`` as indented JSON to ``path`` (creating folders); no-op for None."""
    if path is None:
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2, default=float) + "\n")
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
