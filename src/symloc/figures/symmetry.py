"""Figures of the symmetry judgement (the only symmetry code that imports matplotlib)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symloc.figures._save import save_figure

__all__ = ["plot_judgement", "plot_judgement_grid", "plot_table1_positions"]


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_table1_positions(
    positions: Sequence[Mapping[str, Any]],
    path: str | Path,
    *,
    sensor: str = "paper_15m",
    methods: Sequence[str] = ("judge/area", "judge/mean"),
) -> Path:
    """Like the paper's Figure 12: each room of Table 1 with its robot positions, correct or
    wrong.

    Parameters
    ----------
    positions : sequence of mapping
        ``run_table1(...)["positions"]``: per room ``shape``, ``gv``, ``sensor``,
        ``boundary`` (V, 2), ``positions`` (P, 2) and ``correct`` {method key: (P,) bool}.
    path : path
        PNG file to write.
    sensor : str
        Which sensor's rows to draw.
    methods : sequence of str
        Method keys; the first is drawn as filled dots (green correct, red wrong), the second
        as rings around them.

    Returns
    -------
    Path
    """
    plt = _pyplot()
    rows = [p for p in positions if p["sensor"] == sensor]
    shapes = list(dict.fromkeys(p["shape"] for p in rows))
    gvs = sorted({p["gv"] for p in rows})
    fig, axes = plt.subplots(
        len(shapes), len(gvs), figsize=(3.2 * len(gvs), 3.0 * len(shapes)), squeeze=False
    )
    for ax in axes.ravel():
        ax.set_axis_off()
    for p in rows:
        ax = axes[shapes.index(p["shape"]), gvs.index(p["gv"])]
        ax.set_axis_on()
        b = np.asarray(p["boundary"])
        ax.fill(b[:, 0], b[:, 1], facecolor="0.95", edgecolor="k", lw=1.2)
        xy = np.asarray(p["positions"])
        titles = []
        for j, key in enumerate(methods[:2]):
            ok = np.asarray(p["correct"].get(key, []), dtype=bool)
            if ok.size != xy.shape[0]:
                continue
            if j == 0:
                ax.scatter(*xy[ok].T, s=14, c="tab:green", marker="o", zorder=3)
                ax.scatter(*xy[~ok].T, s=22, c="tab:red", marker="x", zorder=3)
            else:
                ax.scatter(*xy[~ok].T, s=40, facecolors="none", edgecolors="tab:orange", lw=0.8)
            titles.append(f"{key.split('/')[-1]} {int(ok.sum())}/{ok.size}")
        ax.set_title(f"{p['shape']} G-V {p['gv']:g} m\n" + ", ".join(titles), fontsize=8)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6)
    fig.suptitle(
        f"Table 1 positions ({sensor}): dot = {methods[0]} correct (green) / wrong (red x);"
        f" orange ring = {methods[1] if len(methods) > 1 else ''} wrong",
        fontsize=9,
    )
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    return save_figure(fig, path, dpi=110)


def _draw_judgement(ax: Any, scan: Any, report: Any, lines: Any, title: str) -> None:
    """Points, fitted lines, corners, centroid, centre and hallway axis of one scan."""
    pts = scan.to_points().points
    ax.plot(pts[:, 0], pts[:, 1], ".", ms=1.5, color="0.45", label="scan points")
    ax.plot(0, 0, "^", color="k", ms=6, label="sensor (x forward)")
    ax.plot([0, 0.5], [0, 0], "-", color="k", lw=1)
    if lines is not None and lines.segments.size:
        # pieces of fewer than 3 points (edges of depth jumps, clutter) are drawn faintly
        wall = lines.n_points >= 3
        first = True
        for seg, is_wall in zip(lines.segments, wall, strict=True):
            ax.plot(
                seg[:, 0],
                seg[:, 1],
                "-",
                color="tab:green" if is_wall else "0.8",
                lw=1.5 if is_wall else 0.6,
                label="fitted lines (>= 3 points)" if is_wall and first else None,
            )
            first = first and not is_wall
    if report.corners.size:
        c = report.corners
        ax.plot(c[:, 0], c[:, 1], "o", color="tab:blue", ms=4, label="corners")
    if np.all(np.isfinite(report.centroid)):
        ax.plot(*report.centroid, "s", color="tab:orange", ms=5, label="centroid")
    if np.all(np.isfinite(report.center)):
        ax.plot(*report.center, "*", color="tab:red", ms=12, label="centre")
        if np.isfinite(report.axis_angle):
            d = np.array([np.cos(report.axis_angle), np.sin(report.axis_angle)])
            span = float(np.max(np.abs(pts))) if pts.size else 1.0
            ends = report.center + np.outer([-span, span], d)
            ax.plot(ends[:, 0], ends[:, 1], "--", color="tab:red", lw=0.8, label="axis")
    ax.set_title(title, fontsize=7)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=6)


def _order_text(report: Any) -> str:
    """A report's order for a title: ``inf`` for a circle, 0 for an unknown verdict."""
    return "0" if report.order is None else str(report.order)


def plot_judgement(scan: Any, report: Any, path: str | Path, *, lines: Any = None) -> Path:
    """One scan in the sensor frame with the judgement: points, lines, corners, centre.

    Parameters
    ----------
    scan : LaserScan
    report : SymmetryReport
    path : path
        PNG file to write.
    lines : ScanLines, optional
        Fitted lines to draw (:func:`symloc.symmetry.scan_lines`).
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    order = _order_text(report)
    _draw_judgement(
        ax, scan, report, lines, f"{report.kind}, order {order}, symmetric={report.symmetric}"
    )
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def plot_judgement_grid(
    items: Sequence[tuple[Any, Any, Any, str]], path: str | Path, *, title: str, ncols: int = 4
) -> Path:
    """Several judged scans side by side, for a person to check the verdicts.

    Parameters
    ----------
    items : sequence of (LaserScan, SymmetryReport, ScanLines or None, label)
    path : path
        PNG file to write.
    title : str
    ncols : int
        Panels per row.
    """
    plt = _pyplot()
    n = max(len(items), 1)
    ncols = max(1, min(ncols, n))
    nrows = -(-n // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.6 * ncols, 3.6 * nrows + 0.4), squeeze=False)
    for ax in axes.ravel()[len(items) :]:
        ax.axis("off")
    if not items:
        axes[0, 0].text(0.5, 0.5, "no scans", ha="center", va="center")
    for ax, (scan, report, lines, label) in zip(axes.ravel(), items, strict=False):
        order = _order_text(report)
        _draw_judgement(ax, scan, report, lines, f"{label}\n{report.kind}, order {order}")
    if items:
        axes[0, 0].legend(fontsize=6, loc="lower left")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path, dpi=100)
