"""What the localizer did, in words: a logger and a bounded history callers can read."""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Iterator
from typing import overload

__all__ = ["NOTE_HISTORY", "Notes"]

#: How many notes a localizer keeps (a node runs for days; the bench reads the last few).
NOTE_HISTORY = 1000


class Notes:
    """The localizer's notes: each goes to ``logger`` (INFO) and into a history of the last
    ``maxlen``, read like a list (``notes[-1]``, ``notes[-20:]``, ``list(notes)``)."""

    def __init__(self, logger: logging.Logger, maxlen: int = NOTE_HISTORY) -> None:
        self.logger = logger
        self._history: deque[str] = deque(maxlen=maxlen)

    def __call__(self, text: str) -> None:
        """Log ``text`` and keep it."""
        self.logger.info("%s", text)
        self._history.append(text)

    def note_once(self, text: str) -> None:
        """Log ``text`` unless it is the last note already (a state that lasts is said once)."""
        if not self._history or self._history[-1] != text:
            self(text)

    def __len__(self) -> int:
        return len(self._history)

    def __iter__(self) -> Iterator[str]:
        return iter(self._history)

    @overload
    def __getitem__(self, index: int) -> str: ...

    @overload
    def __getitem__(self, index: slice) -> list[str]: ...

    def __getitem__(self, index: int | slice) -> str | list[str]:
        if isinstance(index, slice):
            return list(self._history)[index]
        return self._history[index]

    def __repr__(self) -> str:
        return f"Notes({list(self._history)!r})"
