"""Helpers every experiment shares: printing the configuration, writing JSON."""

from __future__ import annotations

import json
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["add_common_arguments", "print_config", "write_json"]


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
