"""TUM trajectory files (``t x y z qx qy qz qw``), which evo reads, and one answer per scan."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from symloc.files.atomic import atomic_write_text

__all__ = ["TrajectoryPoint", "write_tum"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class TrajectoryPoint:
    """The localizer's answer at one scan: stamp [s], status, the earned pose (3,) or None,
    the tracker's best estimate (3,) earned or not (None if unknown), and the reason."""

    stamp: float
    status: str
    pose: FloatArray | None
    estimate: FloatArray | None = None
    reason: str = ""


def write_tum(path: Path, rows: list[tuple[float, FloatArray]]) -> None:
    """Write poses as a TUM trajectory (``t x y z qx qy qz qw``; z = 0), which evo reads."""
    lines = []
    for t, p in rows:
        h = 0.5 * float(p[2])
        lines.append(f"{t:.9f} {p[0]:.9f} {p[1]:.9f} 0 0 0 {math.sin(h):.12f} {math.cos(h):.12f}")
    atomic_write_text(path, "\n".join(lines) + ("\n" if lines else ""))
