"""Run a command as its own process and measure it: peak resident memory and CPU time.

:func:`run_measured` runs the command under a minimal launcher (``python -S``, a few MiB) that
starts it with ``os.posix_spawnp`` and reaps it with ``os.wait4``, which returns the resource
usage of exactly that process (``ru_maxrss``: its peak resident set size; ``ru_utime +
ru_stime``: its CPU time). So every SLAM run of a benchmark, symloc's or a peer's, is measured
the same way, in a fresh process whose peak memory belongs to that run alone.

Why the launcher: Linux records, at ``exec``, the memory high-water mark of the process image
being replaced into the new program's ``ru_maxrss``; a program started directly from a large
Python process (a sweep worker holding a log) would report at least that process's size. A
worker reused across runs would also report the largest run so far.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from symloc.errors import ConfigurationError

__all__ = ["MeasuredRun", "run_measured"]


@dataclass(frozen=True, slots=True)
class MeasuredRun:
    """Outcome of :func:`run_measured`.

    Attributes
    ----------
    returncode : int
        Exit code (negative: killed by that signal; -9 after a timeout).
    stdout, stderr : str
        What the process printed (decoded, errors replaced).
    peak_rss_mb : float
        Peak resident set size of the process [MiB] (``ru_maxrss``).
    cpu_s : float
        User + system CPU time of the process [s].
    wall_s : float
        Wall-clock time from start to exit [s] (depends on the machine's load).
    timed_out : bool
    """

    returncode: int
    stdout: str
    stderr: str
    peak_rss_mb: float
    cpu_s: float
    wall_s: float
    timed_out: bool = False


def _rss_mb(ru_maxrss: int) -> float:
    # Linux reports kibibytes, macOS bytes
    return ru_maxrss / (1024.0 * 1024.0) if sys.platform == "darwin" else ru_maxrss / 1024.0


#: The launcher: spawn argv[2:], wait for it, write its exit status and rusage to argv[1].
_LAUNCHER = """
import json, os, sys
try:
    pid = os.posix_spawnp(sys.argv[2], sys.argv[2:], os.environ)
except OSError as err:
    print(f"cannot run {sys.argv[2]!r}: {err}", file=sys.stderr)
    sys.exit(127)
_, status, ru = os.wait4(pid, 0)
with open(sys.argv[1] + ".tmp", "w") as fh:  # then renamed: the reader sees all or nothing
    json.dump([status, ru.ru_maxrss, ru.ru_utime + ru.ru_stime], fh)
os.replace(sys.argv[1] + ".tmp", sys.argv[1])
"""


def run_measured(
    cmd: Sequence[str | Path],
    *,
    timeout: float | None = None,
    cwd: str | Path | None = None,
    env: dict[str, str] | None = None,
) -> MeasuredRun:
    """Run ``cmd`` to completion in its own process and measure it (see the module docstring).

    Parameters
    ----------
    cmd : sequence of str or Path
        Program and arguments (no shell).
    timeout : float, optional
        Kill the process after this many seconds (``timed_out`` is then True).
    cwd, env : optional
        As for :class:`subprocess.Popen`.

    The peak memory has a floor of the launcher's own size (about 9 MiB): a program smaller
    than that reports the launcher's figure.

    Raises
    ------
    ConfigurationError
        The program does not exist or cannot be executed.
    """
    args = [str(c) for c in cmd]
    if not args:
        raise ConfigurationError("cmd: expected a program and its arguments")
    if timeout is not None and not timeout > 0:
        raise ConfigurationError(f"timeout: expected > 0 s, got {timeout}")
    with tempfile.TemporaryDirectory(prefix="symloc-measure-") as tmp:
        usage_path = Path(tmp) / "usage.json"
        launcher = [sys.executable, "-S", "-c", _LAUNCHER, str(usage_path), *args]
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            launcher,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            cwd=cwd,
            env=env,
            start_new_session=True,  # a timeout kills the launcher and the program together
        )
        chunks: dict[str, list[bytes]] = {"out": [], "err": []}

        def _drain(name: str, stream: object) -> None:
            read = stream.read  # type: ignore[attr-defined]
            while data := read(65536):
                chunks[name].append(data)

        readers = [
            threading.Thread(target=_drain, args=("out", proc.stdout), daemon=True),
            threading.Thread(target=_drain, args=("err", proc.stderr), daemon=True),
        ]
        for t in readers:
            t.start()
        timed_out = False
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            timed_out = True
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        wall = time.perf_counter() - t0
        for t in readers:
            t.join(timeout=5.0)
        if proc.stdout is not None:
            proc.stdout.close()
        if proc.stderr is not None:
            proc.stderr.close()
        stderr = b"".join(chunks["err"]).decode(errors="replace")
        if timed_out or not usage_path.is_file():
            if proc.returncode == 127 and not timed_out:
                raise ConfigurationError(stderr.strip() or f"cannot run {args[0]!r}")
            return MeasuredRun(
                returncode=-9 if timed_out else proc.returncode,
                stdout=b"".join(chunks["out"]).decode(errors="replace"),
                stderr=stderr,
                peak_rss_mb=float("nan"),
                cpu_s=float("nan"),
                wall_s=wall,
                timed_out=timed_out,
            )
        status, maxrss, cpu = json.loads(usage_path.read_text())
    return MeasuredRun(
        returncode=os.waitstatus_to_exitcode(int(status)),
        stdout=b"".join(chunks["out"]).decode(errors="replace"),
        stderr=stderr,
        peak_rss_mb=_rss_mb(int(maxrss)),
        cpu_s=float(cpu),
        wall_s=wall,
        timed_out=timed_out,
    )
