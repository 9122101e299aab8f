"""Where, when and on what a measurement ran: the provenance a results file carries.

A figure in the README is only as good as the statement of the run behind it: the command, the
commit it ran on, the date, the machine and how loaded it was. :func:`machine` and
:func:`commit` read them from this process; :class:`RunClock` brackets a run with the load
average and the wall time.
"""

from __future__ import annotations

import datetime as _dt
import logging
import os
import platform
import shlex
import subprocess
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "RunClock",
    "command_line",
    "commit",
    "cpus_allowed",
    "machine",
    "peer_source",
    "utc_now",
]

log = logging.getLogger(__name__)

_SOURCE = Path(__file__).resolve().parent


def command_line(argv: Sequence[str], program: str = "symloc") -> str:
    """The command as a user would type it again: ``program`` and ``argv``, shell-quoted."""
    return shlex.join([program, *argv])


def commit(where: Path = _SOURCE) -> str:
    """The git commit of the checkout that holds ``where`` (short hash, ``+dirty`` when the work
    tree has changes), or ``"unknown (not a git checkout)"`` for an installed copy."""

    def git(*args: str) -> str:
        return subprocess.run(
            ["git", *args], cwd=where, capture_output=True, text=True, check=True, timeout=10
        ).stdout.strip()

    try:
        head = git("rev-parse", "--short", "HEAD")
        dirty = git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.SubprocessError) as err:
        log.debug("no git commit for %s: %s", where, err)
        return "unknown (not a git checkout)"
    return f"{head}+dirty" if dirty else head


def cpus_allowed() -> list[int] | None:
    """The cores this process may run on (``taskset``, cgroups' cpusets) when they are fewer
    than the machine's, else ``None`` (every core, or a system that does not say)."""
    try:
        allowed = sorted(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return None
    return allowed if len(allowed) < (os.cpu_count() or len(allowed)) else None


def peer_source(cmd: str, default: str) -> str:
    """What a peer program was built from, for a results file: the first line of
    ``SOURCE.txt`` beside the program that the command ``cmd`` runs (the build scripts of
    ``benchmarks/peers`` write it), else ``default``."""
    words = shlex.split(cmd)
    if not words:
        return default
    try:
        text = (Path(words[0]).parent / "SOURCE.txt").read_text(encoding="utf-8").strip()
    except (OSError, UnicodeDecodeError):
        return default
    return text.splitlines()[0] if text else default


def utc_now() -> str:
    """The current time in UTC, ISO 8601 to the second (``2026-11-28T07:39:12Z``)."""
    now = _dt.datetime.now(_dt.UTC).replace(microsecond=0)
    return now.isoformat().replace("+00:00", "Z")


def _memory_gib() -> float | None:
    try:
        pages = os.sysconf("SC_PHYS_PAGES")
        size = os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None
    return round(pages * size / 2**30, 1)


def _cpu_model() -> str | None:
    """The processor's model name (Linux's ``/proc/cpuinfo``), None where it is not said."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return None


def _numpy_simd() -> list[str]:
    """NumPy's dispatched SIMD targets this processor runs (``X86_V4``, ``AVX512_SPR``, ...):
    trials amplify last-bit differences between them, so two machines with the same code can
    grade a particle filter's trial differently."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    except ImportError:
        return []
    return [name for name in __cpu_dispatch__ if __cpu_features__.get(name)]


def machine() -> dict[str, Any]:
    """The machine as a reader needs it to weigh a timing or compare a run: cores, memory,
    processor (and its model), system, Python, NumPy and the SIMD targets NumPy dispatches to
    here (no host name)."""
    import numpy

    return {
        "cpus": os.cpu_count(),
        "memory_gib": _memory_gib(),
        "processor": platform.processor() or platform.machine(),
        "cpu_model": _cpu_model(),
        "system": f"{platform.system()} {platform.release()}",
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "numpy_simd": _numpy_simd(),
    }


def _load_1min() -> float | None:
    try:
        return round(os.getloadavg()[0], 2)
    except (OSError, AttributeError):
        return None


@dataclass
class RunClock:
    """Commit, wall time and 1-minute load average around a run: create it at the start, call
    :meth:`stop` at the end, then :meth:`load`, :attr:`wall_s` and :attr:`revision`."""

    started: str = field(default_factory=utc_now)
    load_start: float | None = field(default_factory=_load_1min)
    revision: str = field(default_factory=commit)
    """The commit at the start: the code that ran, whatever changes in the tree meanwhile."""
    _t0: float = field(default_factory=time.perf_counter)
    wall_s: float | None = None
    load_end: float | None = None
    finished: str | None = None

    def stop(self) -> RunClock:
        """Record the end of the run (idempotent: the first call counts)."""
        if self.wall_s is None:
            self.wall_s = time.perf_counter() - self._t0
            self.load_end = _load_1min()
            self.finished = utc_now()
        return self

    def load(self) -> dict[str, Any]:
        """The load averages at the start and at the end, and the core count they compare to."""
        return {
            "load_1min_start": self.load_start,
            "load_1min_end": self.load_end,
            "cpus": os.cpu_count(),
        }
