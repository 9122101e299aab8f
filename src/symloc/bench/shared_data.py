"""Where the shared recorded data lives: the real CARMEN laser logs.

Used by the experiments and by ``symloc bench slam`` alike (so neither imports the other).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["CARMEN_LOGS", "find_carmen_dir"]

#: The real laser logs in ``../shared/data/carmen`` (see its README).
CARMEN_LOGS = ("intel", "aces", "freiburg-079")


def find_carmen_dir() -> Path | None:
    """``$SYMLOC_SHARED_DATA/carmen`` or ``<repo>/../shared/data/carmen``, if it exists."""
    env = os.environ.get("SYMLOC_SHARED_DATA")
    cands = [Path(env) / "carmen"] if env else []
    cands.append(Path(__file__).resolve().parents[3] / ".." / "shared" / "data" / "carmen")
    for c in cands:
        if c.is_dir():
            return c.resolve()
    return None
