"""Files as symloc reads and writes them: atomic writes (:mod:`symloc.files.atomic`) and
bounded reads of untrusted input (:mod:`symloc.files.bounded`). The bottom layer: it imports
nothing else of symloc (errors are raised as the caller's class)."""

from __future__ import annotations

__all__: list[str] = []
