"""The one way every figure is written: create the folder, save, close, return the path."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from symloc.files.atomic import atomic_path

__all__ = ["save_figure"]


def save_figure(fig: Any, path: str | Path, *, dpi: float | None = None) -> Path:
    """Save ``fig`` as ``path`` (folders created; atomically), close it, and return the path.

    ``dpi=None`` keeps matplotlib's ``savefig.dpi`` default.
    """
    import matplotlib.pyplot as plt

    out = Path(path)
    try:
        # atomically: a figure overwritten by a killed run stays the previous one
        with atomic_path(out) as tmp:
            fig.savefig(tmp, dpi=dpi)
    finally:
        plt.close(fig)
    return out
