"""Atomic file writes: a reader sees the old file or the new one, never a torn one.

Every file symloc writes goes through this module. The recipe is the classic one: write a
temporary file in the target's own folder (so that the rename stays on one file system), flush
and ``fsync`` it, ``os.replace`` it over the target (atomic on POSIX), then ``fsync`` the folder
so that the rename itself survives a power cut. A process killed at any point leaves the
target as it was or as it is meant to be, plus at worst a stray temporary file named
``.<name>.<random>.tmp<suffix>`` (see :func:`remove_stale_temporaries`).

The temporary file keeps the target's suffix, so writers that infer a format from the name
(matplotlib's ``savefig``, ``numpy.savez``, OpenCV's ``imwrite``) can write it directly
(:func:`atomic_path`). It is created with the permissions an ordinary ``open(path, "w")``
would give (``0o666`` less the umask), or the mode of the file it replaces.

A pair of files that must match (a map's YAML and its image) cannot be replaced together
atomically; :func:`symloc.grid.map_io.save_map` writes the image under a name unique to the
write first and the YAML that names it last.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import secrets
import stat
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, Any

__all__ = [
    "atomic_open",
    "atomic_path",
    "atomic_write_bytes",
    "atomic_write_text",
    "fsync_folder",
    "remove_stale_temporaries",
    "temporary_name",
]

log = logging.getLogger(__name__)

#: Age after which :func:`remove_stale_temporaries` treats a temporary file as abandoned (a
#: writer that is still alive finishes its file long before).
STALE_SECONDS = 600.0


_TEMPORARY = re.compile(r"\.(?P<target>.+)\.[0-9a-f]{12}\.tmp(?P<suffix>.*)")


def temporary_name(target: Path) -> Path:
    """A fresh temporary path next to ``target``: ``.<name>.<12 hex>.tmp<suffix>``."""
    return target.with_name(f".{target.name}.{secrets.token_hex(6)}.tmp{target.suffix}")


def temporary_target(name: str) -> str | None:
    """The file name that a temporary file called ``name`` (as :func:`temporary_name` names
    them) was to become; None for any other name."""
    found = _TEMPORARY.fullmatch(name)
    if found is None or Path(found["target"]).suffix != found["suffix"]:
        return None
    return found["target"]


def _create_temporary(target: Path) -> tuple[Path, int]:
    """Create (exclusively) a temporary file next to ``target``; return its path and fd."""
    try:
        mode = stat.S_IMODE(target.stat().st_mode)
    except OSError:
        mode = None
    for _ in range(100):
        tmp = temporary_name(target)
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
        except FileExistsError:
            continue
        if mode is not None:
            with contextlib.suppress(OSError):
                os.fchmod(fd, mode)
        return tmp, fd
    raise FileExistsError(
        f"{target}: cannot create a temporary file next to it"
    )  # pragma: no cover


def fsync_folder(folder: Path) -> None:
    """``fsync`` a folder so that renames in it are durable (a no-op where unsupported)."""
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _commit(tmp: Path, target: Path) -> None:
    os.replace(tmp, target)
    fsync_folder(target.parent)


@contextlib.contextmanager
def atomic_open(
    path: str | Path, mode: str = "w", *, encoding: str | None = "utf-8", newline: str | None = None
) -> Iterator[IO[Any]]:
    """Open a temporary file for writing that replaces ``path`` when the block ends.

    ``mode`` is ``"w"`` (text) or ``"wb"``. If the block raises, the temporary file is removed
    and ``path`` is untouched. The folder of ``path`` is created if missing.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open: mode must be 'w' or 'wb', got {mode!r}")
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp, fd = _create_temporary(target)
    try:
        if mode == "wb":
            fh: IO[Any] = os.fdopen(fd, "wb")
        else:
            fh = os.fdopen(fd, "w", encoding=encoding, newline=newline)
        with fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        _commit(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path."""
    with atomic_open(path, "wb") as fh:
        fh.write(data)
    return Path(path)


def atomic_write_text(path: str | Path, text: str, *, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically; returns the path."""
    with atomic_open(path, "w", encoding=encoding) as fh:
        fh.write(text)
    return Path(path)


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path (same folder, same suffix) for a writer that wants a file name.

    The block writes the file named by the yielded path (``fig.savefig(tmp)``,
    ``np.savez(tmp, ...)``); when it ends, the file is fsynced and renamed over ``path``. If the
    block raises or leaves no file, ``path`` is untouched.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp, fd = _create_temporary(target)
    os.close(fd)
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        _commit(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def remove_stale_temporaries(
    target: Path, *, older_than: float = STALE_SECONDS, extra: Callable[[Path], bool] | None = None
) -> int:
    """Remove temporary files of ``target`` left by killed writers; returns how many.

    Only files named as :func:`temporary_name` names them for ``target`` (or accepted by
    ``extra``) and not modified for ``older_than`` seconds are removed, so a writer that is
    still running keeps its file.
    """
    folder = target.parent
    now = time.time()
    removed = 0
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return 0
    for entry in entries:
        name = entry.name
        ours = temporary_target(name) == target.name
        if not ours and not (extra is not None and extra(Path(entry.path))):
            continue
        try:
            if not entry.is_file(follow_symlinks=False):
                continue
            if now - entry.stat(follow_symlinks=False).st_mtime < older_than:
                continue
            os.unlink(entry.path)
            removed += 1
        except OSError:
            continue
    if removed:
        log.info("%s: removed %d abandoned temporary file(s)", folder, removed)
    return removed
