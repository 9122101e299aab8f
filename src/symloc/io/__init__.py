"""Readers for recorded data: CARMEN laser logs (:mod:`symloc.io.carmen`), ROS bags."""

from __future__ import annotations

__all__: list[str] = []
