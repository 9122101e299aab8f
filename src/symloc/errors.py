"""The one family of exceptions that symloc raises.

Every error a user can act on derives from :class:`SymlocError`. Subclasses that describe bad
values also derive from :class:`ValueError`, so code that already catches ``ValueError`` keeps
working. Boundary code (file readers, the ROS node) wraps third-party exceptions with
``raise ... from err`` so that a caller sees one family.
"""

from __future__ import annotations

__all__ = [
    "ConfigurationError",
    "DataFormatError",
    "DatabaseError",
    "MapFileError",
    "SymlocError",
    "VocabularyFileError",
    "WorldError",
]


class SymlocError(Exception):
    """Base class of every symloc exception."""


class ConfigurationError(SymlocError, ValueError):
    """A setting or argument is out of range or inconsistent (the message names it)."""


class DataFormatError(SymlocError, ValueError):
    """A sensor message or log record is malformed (the message names the field)."""


class MapFileError(SymlocError, ValueError):
    """A map_server YAML/image pair cannot be read or written."""


class VocabularyFileError(SymlocError, ValueError):
    """A vocabulary file is corrupt or truncated (the message names the line or byte)."""


class DatabaseError(SymlocError):
    """The visual-map database is not a symloc database, is newer, or is damaged."""


class WorldError(SymlocError, ValueError):
    """A simulated world is degenerate (zero-length wall, self-intersecting room, ...)."""
