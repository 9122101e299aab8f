"""Small stateful rules the localizer's phases share (after beluga's ``policies``)."""

from __future__ import annotations

from symloc.errors import ConfigurationError

__all__ = ["Streak"]


class Streak:
    """Counts events until there have been ``n`` of them.

    :meth:`hit` counts one and says whether ``n`` are reached; :meth:`miss` starts over (a
    streak of consecutive events), :meth:`reset` too (the rule's owner starts over). A caller
    that never calls :meth:`miss` counts events since the last reset instead.

    >>> s = Streak(2)
    >>> s.hit(), s.hit(), s.hit()
    (False, True, True)
    >>> s.miss(); s.hit()
    False
    """

    __slots__ = ("_count", "n")

    def __init__(self, n: int) -> None:
        if not isinstance(n, int) or isinstance(n, bool) or n < 1:
            raise ConfigurationError(f"Streak.n: expected an integer >= 1, got {n!r}")
        self.n = n
        self._count = 0

    @property
    def count(self) -> int:
        """Events counted since the last miss or reset."""
        return self._count

    @property
    def reached(self) -> bool:
        """True when at least ``n`` events were counted."""
        return self._count >= self.n

    def hit(self) -> bool:
        """Count one event; True when ``n`` (or more) are reached."""
        self._count += 1
        return self.reached

    def miss(self) -> None:
        """The streak is broken: start over."""
        self._count = 0

    def reset(self) -> None:
        """Start over (same as :meth:`miss`, named for a restart rather than a broken streak)."""
        self._count = 0

    def __repr__(self) -> str:
        return f"Streak({self._count}/{self.n})"
