"""Figures of the symmetry judgement (the only symmetry code that imports matplotlib)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["plot_judgement", "plot_table1_positions"]


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
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def plot_judgement(scan: Any, report: Any, path: str | Path) -> Path:
    """One scan in the sensor frame with the judgement: points, corners, centroid, centre.

    Parameters
    ----------
    scan : LaserScan
    report : SymmetryReport
    path : path
        PNG file to write.
    """
    plt = _pyplot()
    pts = scan.to_points().points
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(pts[:, 0], pts[:, 1], ".", ms=2, color="0.3", label="scan points")
    ax.plot(0, 0, "^", color="k", label="sensor")
    if report.corners.size:
        c = np.vstack([report.corners, report.corners[:1]])
        ax.plot(c[:, 0], c[:, 1], "-o", color="tab:blue", ms=4, lw=1, label="walls / corners")
    if np.all(np.isfinite(report.centroid)):
        ax.plot(
            *report.centroid, "s", color="tab:orange", label=f"{report.centroid_method} centroid"
        )
    if np.all(np.isfinite(report.center)):
        ax.plot(*report.center, "*", color="tab:red", ms=12, label="centre")
    order = "inf" if report.continuous else report.order
    ax.set_title(f"{report.kind}, order {order}, symmetric={report.symmetric}", fontsize=9)
    ax.set_aspect("equal")
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
