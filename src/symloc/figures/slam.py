"""Figures for mapping and SLAM (the only slam code that imports matplotlib)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symloc.figures._save import save_figure

__all__ = ["map_trajectory_figure", "slam_bench_figure", "slam_summary_figure"]


#: Largest image side [pixels] drawn as it is; a larger map is drawn averaged over blocks of
#: cells (the 8-inch, 120-dpi figure shows about 900 pixels across anyway).
_MAX_IMAGE_SIDE = 2048

#: Grid rows converted to gray at once (bounds the float64 temporaries of a large map).
_BAND_ROWS = 128


def _grid_image(grid: Any) -> np.ndarray:
    """Gray image ``(h, w)`` of ``grid.data (H, W)``: 1 free, 0 occupied, 0.5 unknown.

    A map wider or taller than ``_MAX_IMAGE_SIDE`` cells is averaged over ``f x f`` blocks
    (``f`` the smallest factor that brings it under; a partial block at the top or right
    edge is averaged over its cells), converting a band of rows at a time, so that drawing a
    map of tens of millions of cells does not hold several float64 copies of it.
    """
    data = grid.data
    h, w = data.shape
    f = -(-max(h, w) // _MAX_IMAGE_SIDE)
    if f <= 1:
        return np.where(data < 0, 0.5, 1.0 - data / 100.0)
    hb, wb = -(-h // f), -(-w // f)
    out = np.empty((hb, wb), dtype=np.float64)
    step = max(1, _BAND_ROWS // f) * f
    col_counts = np.bincount(np.arange(w) // f, minlength=wb).astype(np.float64)
    for a in range(0, h, step):
        band = data[a : a + step]
        gray = np.where(band < 0, 0.5, 1.0 - band / 100.0)
        rows = np.add.reduceat(gray, np.arange(0, gray.shape[0], f), axis=0)
        sums = np.add.reduceat(rows, np.arange(0, w, f), axis=1)
        n_rows = np.bincount(np.arange(gray.shape[0]) // f).astype(np.float64)
        out[a // f : a // f + sums.shape[0]] = sums / n_rows[:, None] / col_counts[None, :]
    return out


def _known_box(data: np.ndarray) -> np.ndarray | None:
    """``[[row_min, col_min], [row_max, col_max]]`` of the cells ``>= 0``, or None."""
    known = data >= 0
    rows = np.flatnonzero(known.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(known.any(axis=0))
    return np.array([[rows[0], cols[0]], [rows[-1], cols[-1]]])


def map_trajectory_figure(
    grid: Any,
    poses: np.ndarray,
    path: str | Path,
    *,
    reference: np.ndarray | None = None,
    odometry: np.ndarray | None = None,
    loop_nodes: Sequence[int] = (),
    title: str = "",
    keyframes: np.ndarray | None = None,
) -> Path:
    """Save a PNG of ``grid`` with the SLAM trajectory ``poses`` (N, 3) on top.

    ``reference`` and ``odometry`` (N, 3), if given, are drawn too (already in the map frame
    or aligned by the caller); ``loop_nodes`` marks nodes that received a loop closure;
    ``keyframes`` (K, 3) x [m], y [m], theta [rad]: the visual map's keyframes, drawn as arrows
    along the camera's heading.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 8), dpi=120)
    x0, x1, y0, y1 = grid.extent()
    ax.imshow(
        _grid_image(grid), cmap="gray", origin="lower", extent=(x0, x1, y0, y1), vmin=0, vmax=1
    )
    if odometry is not None:
        ax.plot(
            odometry[:, 0],
            odometry[:, 1],
            "-",
            color="tab:orange",
            lw=0.8,
            alpha=0.7,
            label="odometry",
        )
    if reference is not None:
        ax.plot(reference[:, 0], reference[:, 1], "-", color="tab:green", lw=1.2, label="reference")
    ax.plot(poses[:, 0], poses[:, 1], "-", color="tab:blue", lw=1.0, label="SLAM")
    if len(loop_nodes):
        idx = np.unique(np.asarray(loop_nodes, dtype=int))
        ax.plot(poses[idx, 0], poses[idx, 1], ".", color="tab:red", ms=3, label="loop closure")
    if keyframes is not None and len(keyframes):
        kf = np.asarray(keyframes, dtype=np.float64).reshape(-1, 3)
        ax.quiver(
            kf[:, 0],
            kf[:, 1],
            np.cos(kf[:, 2]),
            np.sin(kf[:, 2]),
            color="tab:purple",
            angles="xy",
            scale_units="xy",
            scale=3.0,
            width=0.004,
            label=f"keyframes ({kf.shape[0]})",
        )
    box = _known_box(grid.data)
    if box is not None:
        c = grid.cell_to_world(box)
        xs = np.concatenate([c[:, 0], poses[:, 0]])
        ys = np.concatenate([c[:, 1], poses[:, 1]])
        ax.set_xlim(xs.min() - 1.0, xs.max() + 1.0)
        ax.set_ylim(ys.min() - 1.0, ys.max() + 1.0)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(loc="upper right", fontsize=8)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)


def slam_summary_figure(rows: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """Bar charts of ATE RMSE (SLAM vs odometry) and real-time factor per run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [r["name"] for r in rows]
    x = np.arange(len(rows))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4), dpi=120)
    a1.bar(x - 0.2, [r["ate_rmse_m"] for r in rows], 0.4, label="SLAM")
    a1.bar(x + 0.2, [r["ate_odometry_rmse_m"] for r in rows], 0.4, label="odometry")
    a1.axhline(0.10, color="k", ls="--", lw=0.8, label="0.10 m target")
    a1.set_yscale("log")
    a1.set_xticks(x, names, rotation=20)
    a1.set_ylabel("ATE RMSE [m]")
    a1.legend(fontsize=8)
    a2.bar(x, [r["realtime_factor_cpu"] for r in rows], 0.5, label="CPU time")
    a2.bar(x, [r["realtime_factor_wall"] for r in rows], 0.25, label="wall clock")
    a2.axhline(10.0, color="k", ls="--", lw=0.8, label="10x target")
    a2.set_xticks(x, names, rotation=20)
    a2.set_ylabel("data duration / processing time")
    a2.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path)


def slam_bench_figure(
    summary: dict[str, Any], path: str | Path, *, title: str = "", target: float | None = None
) -> Path:
    """``symloc bench slam``: per log and system, ATE RMSE (mean over seeds, bar; worst, dot)
    and peak memory (bar), from :func:`symloc.bench.slam_bench.summarize`'s ``logs``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    logs = summary["logs"]
    names = sorted(logs)
    systems = sorted({s for lg in logs.values() for s in lg}, key=lambda s: (s != "symloc", s))
    x = np.arange(len(names))
    w = 0.8 / max(len(systems), 1)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(10, 7), dpi=120, sharex=True)
    for k, sname in enumerate(systems):
        off = (k - (len(systems) - 1) / 2) * w
        mean = [logs[n].get(sname, {}).get("ate_mean_m") for n in names]
        worst = [logs[n].get(sname, {}).get("ate_worst_m") for n in names]
        mem = [logs[n].get(sname, {}).get("peak_rss_mb") for n in names]

        def _nan(v: list[Any]) -> list[float]:
            return [float("nan") if u is None else float(u) for u in v]

        bars = a1.bar(x + off, _nan(mean), w, label=f"{sname}: mean over seeds")
        a1.plot(x + off, _nan(worst), "v", color=bars.patches[0].get_facecolor(), ms=5)
        a2.bar(x + off, _nan(mem), w, label=sname)
    if target is not None:
        a1.axhline(target, color="k", ls="--", lw=0.8, label=f"{target:g} m target")
    a1.set_yscale("log")
    a1.set_ylabel("ATE RMSE [m] (triangle: worst seed)")
    a1.legend(fontsize=8)
    a2.axhline(300.0, color="k", ls="--", lw=0.8, label="300 MB target")
    a2.set_ylabel("peak RSS [MB]")
    a2.set_xticks(x, names, rotation=20)
    a2.legend(fontsize=8)
    if title:
        a1.set_title(title, fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)
