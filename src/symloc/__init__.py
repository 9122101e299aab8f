"""symloc: localize a mobile robot in symmetric rooms.

Laser-only Monte Carlo localization cannot tell apart the poses that a symmetric room
(square, regular polygon, circle, rectangle, corridor) maps onto each other. symloc judges
symmetry from one laser scan, drives to the room's centre, decides the heading from camera
images against a bag-of-words visual map, and hands the decided pose back to AMCL.

Conventions (units, frames, angle wrapping, grid indexing) are written once in
``docs/conventions.md``.
"""

from __future__ import annotations

__version__ = "0.1.0"

__all__ = ["__version__"]
