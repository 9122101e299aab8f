"""Figure of a replayed (or recorded) run: map, true path, estimated poses by status."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from symloc.figures._save import save_figure

__all__ = ["plot_replay"]

_COLOURS = {
    "tracking": "tab:green",
    "ambiguous": "tab:orange",
    "going_to_centre": "tab:blue",
    "deciding": "tab:purple",
    "lost": "tab:red",
}


#: Largest side [cells] of the map image drawn; a larger map is drawn in blocks of cells.
MAX_IMAGE_SIDE = 1024


def _map_image(data: np.ndarray, max_side: int = MAX_IMAGE_SIDE) -> np.ndarray:
    """Grey levels in [0, 1] (float32) of an occupancy grid's ``data`` (H, W) int8 (-1 unknown,
    0..100): 1 free, 0 occupied, 0.75 unknown. A grid with a side over ``max_side`` cells is
    reduced to blocks of k x k cells (k the smallest that fits; the last row and column of
    blocks may be narrower), each as dark as its darkest cell so that thin walls stay drawn:
    the map's axes are about 750 pixels wide, and the full grid as float64 with matplotlib's
    RGBA copies was gigabytes for a map of 8,192 x 8,192 cells."""
    level = np.where(data < 0, np.int8(25), data)  # unknown as 25 % occupied: grey 0.75
    k = -(-max(level.shape) // max_side)
    if k > 1:
        level = np.maximum.reduceat(level, np.arange(0, level.shape[0], k), axis=0)
        level = np.maximum.reduceat(level, np.arange(0, level.shape[1], k), axis=1)
    return 1.0 - level.astype(np.float32) / np.float32(100.0)


def plot_replay(
    path: str | Path,
    *,
    grid: Any,
    trajectory: Any,
    truth: Any = None,
    particles: Any = None,
    title: str = "",
) -> Path:
    """Save a PNG: the occupancy grid, the true path (if known), the tracked estimates, and the
    status over time. ``trajectory`` is a list of ``TrajectoryPoint``; ``truth`` (T, 4)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, axs) = plt.subplots(1, 2, figsize=(12, 5.5), gridspec_kw={"width_ratios": [1.3, 1.0]})
    if grid is not None:
        img = _map_image(np.asarray(grid.data))
        ax.imshow(img, cmap="gray", origin="lower", extent=grid.extent(), vmin=0, vmax=1)
    tr = np.asarray(truth if truth is not None else np.zeros((0, 4)), dtype=float).reshape(-1, 4)
    if len(tr):
        ax.plot(tr[:, 1], tr[:, 2], "k-", lw=1.2, label="ground truth")
        ax.plot(tr[0, 1], tr[0, 2], "ko", ms=6, label="start (kidnapped)")
    if particles is not None and len(particles):
        p = np.asarray(particles)
        ax.plot(p[:, 0], p[:, 1], ".", ms=1, color="tab:gray", alpha=0.5, label="final particles")
    tracked = np.array([[pt.stamp, *pt.pose] for pt in trajectory if pt.pose is not None])
    if len(tracked):
        ax.quiver(
            tracked[:, 1],
            tracked[:, 2],
            np.cos(tracked[:, 3]),
            np.sin(tracked[:, 3]),
            color="tab:green",
            scale=25,
            width=0.004,
            label="symloc pose (tracking)",
        )
    if len(tr):
        pad = 1.0
        ax.set_xlim(tr[:, 1].min() - pad - 2, tr[:, 1].max() + pad + 2)
        ax.set_ylim(tr[:, 2].min() - pad - 2, tr[:, 2].max() + pad + 2)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(title or "replay")
    names = list(_COLOURS)
    t = np.array([pt.stamp for pt in trajectory])
    s = np.array([names.index(pt.status) if pt.status in names else -1 for pt in trajectory])
    for i, name in enumerate(names):
        sel = s == i
        axs.plot(t[sel], s[sel], "s", ms=3, color=_COLOURS[name], label=name)
    axs.set_yticks(range(len(names)), names)
    axs.set_xlabel("time [s]")
    axs.set_title("status at each scan")
    if len(tr) and len(tracked):
        err = []
        for row in tracked:
            j = int(np.argmin(np.abs(tr[:, 0] - row[0])))
            err.append(np.hypot(*(row[1:3] - tr[j, 1:3])))
        ax2 = axs.twinx()
        ax2.plot(tracked[:, 0], np.asarray(err) * 100, "g-", lw=0.8)
        ax2.set_ylabel("position error while tracking [cm]", color="tab:green")
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)
