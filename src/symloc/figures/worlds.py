"""A gallery of simulated worlds: each seen from above with its computed symmetry order."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symloc.figures._save import save_figure
from symloc.figures.world import plot_world
from symloc.sim.symmetry_truth import truth_order
from symloc.symmetry.order import SymmetryOrder

__all__ = ["gallery_figure"]


def _order_text(order: SymmetryOrder) -> str:
    if order.is_circle:
        return "order 0 (continuous)"
    if not order.symmetric:
        return "order 1 (none)"
    return f"order {order}"


def gallery_figure(
    rooms: Sequence[tuple[str, Any]],
    path: str | Path,
    *,
    lidar_height: float | None = 0.3,
    t: float = 0.0,
    columns: int = 4,
) -> Path:
    """Draw worlds in a grid and write the PNG.

    Parameters
    ----------
    rooms : sequence of (title, Room)
        Each :class:`~symloc.sim.rooms.Room` is drawn from above (its world at time ``t`` [s]
        with the people where they are then, their paths dotted), with its centre (a cross when
        the order is not 1) and its computed order in the title.
    path : str or Path
        Where to write the PNG.
    lidar_height : float or None
        Primitives no taller than this [m] are dashed.
    columns : int
        Panels per row.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(rooms)
    cols = max(1, min(columns, n))
    rows = max(1, math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.6 * rows), squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    for ax, (title, room) in zip(axes.ravel(), rooms, strict=False):
        plot_world(ax, room.world_at(t), lidar_height=lidar_height)
        for person in room.people:
            p = person.path
            ax.plot(p[:, 0], p[:, 1], ":", color="darkorange", lw=1.0)
        c = np.asarray(room.center)
        ax.plot(c[0], c[1], "+" if room.order != 1 else ".", color="crimson", ms=10, mew=2)
        b = np.asarray(room.boundary)
        pad = 0.08 * float(np.ptp(b, axis=0).max())
        ax.set_xlim(b[:, 0].min() - pad, b[:, 0].max() + pad)
        ax.set_ylim(b[:, 1].min() - pad, b[:, 1].max() + pad)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(f"{title}\n{_order_text(truth_order(room.order))}", fontsize=9)
    fig.suptitle(
        "generated worlds (navy: textured wall, tan: board, brown: furniture, light blue: glass,"
        " black: dark, orange: people, dashed: below the lidar plane, +: symmetry centre)",
        fontsize=9,
    )
    fig.tight_layout()
    return save_figure(fig, path, dpi=90)
