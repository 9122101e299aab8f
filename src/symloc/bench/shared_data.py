"""Where the shared recorded data lives: the real CARMEN laser logs.

Used by the experiments and by ``symloc bench slam`` alike (so neither imports the other).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from symloc.errors import ConfigurationError

__all__ = ["CARMEN_LOGS", "carmen_log_file", "carmen_log_paths", "find_carmen_dir"]

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


def carmen_log_file(folder: Path, name: str) -> Path:
    """The file of log ``name`` in ``folder``: ``<name>-corrected.log.gz``."""
    return Path(folder) / f"{name}-corrected.log.gz"


def carmen_log_paths(
    names: Sequence[str], data: Path | None, *, option: str = "--logs"
) -> dict[str, Path]:
    """The file of every requested CARMEN log, checked before any work starts.

    ``data`` is the folder given with ``--data`` (None: :func:`find_carmen_dir`). Raises
    :class:`~symloc.errors.ConfigurationError` naming the folder and each missing log when the
    folder cannot be found or a requested log is not in it: a command never skips what it was
    asked to run and then reports success.
    """
    folder = data if data is not None else find_carmen_dir()
    if folder is None:
        raise ConfigurationError(
            f"{option} {' '.join(names)}: the CARMEN logs were not found (no --data DIR,"
            " $SYMLOC_SHARED_DATA/carmen or ../shared/data/carmen); pass --data DIR with"
            " <name>-corrected.log.gz files"
        )
    folder = Path(folder)
    if not folder.is_dir():
        raise ConfigurationError(
            f"--data {folder}: the CARMEN logs' folder was not found (not a folder); expected"
            " one with <name>-corrected.log.gz files"
        )
    paths = {name: carmen_log_file(folder, name) for name in dict.fromkeys(names)}
    missing = [f"{n} ({p.name})" for n, p in paths.items() if not p.is_file()]
    if missing:
        raise ConfigurationError(
            f"{option}: not found in {folder}: {', '.join(missing)}; expected"
            " <name>-corrected.log.gz files there"
        )
    return paths
