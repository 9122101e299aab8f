"""Input files read with bounds: regular files only, a size cap, YAML of bounded depth.

Every file symloc reads as a whole (map YAML, world files, parameter files, vocabularies)
goes through :func:`read_bytes_bounded`: the path is opened without blocking and refused
unless it is a regular file (a FIFO would block the reader forever, ``/dev/zero`` never
ends and reports 0 bytes), and at most ``max_bytes`` are read. :func:`load_yaml_bounded`
then parses YAML refusing nesting deeper than :data:`MAX_YAML_DEPTH` (PyYAML recurses once
per level: deep nesting ends in ``RecursionError``) and more than :data:`MAX_YAML_ALIASES`
aliases (a "billion laughs" document expands exponentially in whoever walks it).

Errors are raised as the caller's exception class (``error``), so each loader keeps its
family (:class:`~symloc.errors.MapFileError`, :class:`~symloc.errors.WorldError`,
:class:`~symloc.errors.ConfigurationError`), with the file and what was expected.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path
from typing import Any

import yaml

__all__ = [
    "MAX_PARAMS_FILE_BYTES",
    "MAX_YAML_ALIASES",
    "MAX_YAML_DEPTH",
    "load_yaml_bounded",
    "read_bytes_bounded",
    "read_text_bounded",
]

#: Largest parameter file read [bytes] (nav2's full params file is about 12 KB).
MAX_PARAMS_FILE_BYTES = 4 * 2**20
#: Deepest nesting of YAML collections accepted (nav2's params files nest about 6 levels).
MAX_YAML_DEPTH = 64
#: Most aliases (``*name``) accepted in one YAML document.
MAX_YAML_ALIASES = 256

_KINDS = {
    stat.S_IFIFO: "a FIFO",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
    stat.S_IFDIR: "a folder",
}


def read_bytes_bounded(
    path: str | Path, max_bytes: int, *, what: str, error: type[Exception]
) -> bytes:
    """The bytes of the regular file ``path``, at most ``max_bytes`` of them.

    ``what`` names the file's role in messages (``"map YAML"``, ``"the world file"``).

    Raises
    ------
    error
        ``path`` is missing, unreadable, its name too long, not a regular file (FIFO, device,
        folder, socket) or larger than ``max_bytes``; the message names the file, its role
        and the bound.
    """
    p = Path(path)
    try:
        # O_NONBLOCK: opening a FIFO with no writer returns at once instead of waiting
        fd = os.open(p, os.O_RDONLY | os.O_CLOEXEC | getattr(os, "O_NONBLOCK", 0))
    except OSError as err:
        if err.errno == errno.ENAMETOOLONG:
            raise error(f"{p}: the name of {what} is too long ({err.strerror})") from err
        raise error(f"{p}: cannot read {what} ({err.strerror})") from err
    except ValueError as err:  # a NUL byte in the name
        raise error(f"{str(p)!r}: cannot read {what} ({err})") from err
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            kind = _KINDS.get(stat.S_IFMT(st.st_mode), "not a regular file")
            raise error(f"{p}: {what} is {kind}; expected a regular file")
        if st.st_size > max_bytes:
            raise error(f"{p}: {what} has {st.st_size:,} bytes; at most {max_bytes:,} are read")
        chunks: list[bytes] = []
        left = min(st.st_size, max_bytes) + 1  # one more: a file that grew is noticed
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 24))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
    except OSError as err:
        raise error(f"{p}: cannot read {what} ({err.strerror})") from err
    finally:
        os.close(fd)
    data = b"".join(chunks)
    if len(data) > max_bytes:  # it grew while being read
        raise error(f"{p}: {what} has more than {max_bytes:,} bytes; at most that is read")
    return data


def read_text_bounded(
    path: str | Path, max_bytes: int, *, what: str, error: type[Exception]
) -> str:
    """:func:`read_bytes_bounded`, decoded as UTF-8 (an error names the first bad byte)."""
    data = read_bytes_bounded(path, max_bytes, what=what, error=error)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise error(f"{path}: {what} is not UTF-8 text (byte {err.start} is not UTF-8)") from err


class _BoundedLoader(yaml.SafeLoader):  # type: ignore[misc]  # PyYAML is untyped here
    """PyYAML's safe loader, refusing deep nesting and many aliases while composing."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0
        self._aliases = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_YAML_ALIASES:
                raise yaml.composer.ComposerError(
                    None,
                    None,
                    f"more than {MAX_YAML_ALIASES} aliases",
                    self.peek_event().start_mark,
                )
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                raise yaml.composer.ComposerError(
                    None,
                    None,
                    f"collections nested deeper than {MAX_YAML_DEPTH} levels",
                    self.peek_event().start_mark,
                )
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def load_yaml_bounded(text: str, *, where: str, error: type[Exception]) -> Any:
    """Parse one YAML document (safe types only) of bounded nesting and aliases.

    Raises
    ------
    error
        ``where: not valid YAML (...)`` for a syntax error, nesting deeper than
        :data:`MAX_YAML_DEPTH` or more than :data:`MAX_YAML_ALIASES` aliases.
    """
    try:
        loader = _BoundedLoader(text)  # its reader refuses control characters at once
        try:
            return loader.get_single_data()
        finally:
            loader.dispose()
    except yaml.YAMLError as err:
        raise error(f"{where}: not valid YAML ({err})") from err
    except RecursionError as err:  # pragma: no cover - the depth bound comes first
        raise error(f"{where}: YAML nested too deeply") from err
