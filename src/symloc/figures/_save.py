"""The one way every figure is written: create the folder, save, close, return the path."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["save_figure"]


def save_figure(fig: Any, path: str | Path, *, dpi: float | None = None) -> Path:
    """Save ``fig`` as ``path`` (folders created), close it, and return the path.

    ``dpi=None`` keeps matplotlib's ``savefig.dpi`` default.
    """
    import matplotlib.pyplot as plt

    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out
