"""Figures of the localizer: Table 2 (Algorithm 2), the demo story, the localization results."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symloc.figures._save import save_figure

__all__ = ["demo_figure", "localization_figure", "table2_figure"]


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def table2_figure(results: Sequence[Any], path: Path) -> Path:
    """Start positions coloured by the final error, paths, and the error distribution."""
    plt = _plt()
    n = len(results)
    fig, axes = plt.subplots(2, n, figsize=(4.2 * n, 8.0), squeeze=False)
    for i, res in enumerate(results):
        ax = axes[0, i]
        half = res.side / 2
        ax.plot([-half, half, half, -half, -half], [-half, -half, half, half, -half], "k-")
        for run in res.runs:
            ax.plot(run.path[:, 0], run.path[:, 1], "-", color="0.7", lw=0.6)
        err = res.errors_mm
        sc = ax.scatter(
            res.starts[:, 0], res.starts[:, 1], c=err, cmap="viridis", s=25, vmin=0, vmax=15
        )
        fig.colorbar(sc, ax=ax, label="final error [mm]")
        ax.plot(0, 0, "r+", ms=12)
        ax.set_aspect("equal")
        ax.set_title(f"{res.preset}: starts and paths")
        ax2 = axes[1, i]
        ends = np.array([r.path[-1, :2] for r in res.runs]) * 1000.0
        for r_mm, style in ((5, "g-"), (10, "b-"), (15, "r-")):
            t = np.linspace(0, 2 * np.pi, 200)
            ax2.plot(r_mm * np.cos(t), r_mm * np.sin(t), style, lw=0.8, label=f"{r_mm} mm")
        ax2.plot(ends[:, 0], ends[:, 1], "k.", ms=4)
        ax2.set_aspect("equal")
        ax2.set_xlim(-18, 18)
        ax2.set_ylim(-18, 18)
        sh = res.shares()
        ax2.set_title(
            f"{res.preset}: final positions [mm]\n{100 * sh['5']:.0f} / {100 * sh['10']:.0f} / "
            f"{100 * sh['15']:.0f} % within 5 / 10 / 15 mm",
            fontsize=10,
        )
        ax2.legend(loc="upper right", fontsize=7)
    fig.suptitle("Table 2: Algorithm 2 (go to the centre) from many start positions")
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def _view(story: Any) -> tuple[float, float, float, float]:
    """The map panels' limits [m]: the room's outline with a margin (a square around the
    centre when the outline is unknown)."""
    box = getattr(story, "room_box", None)
    if box is None:
        x0, y0 = story.room_center
        r = story.room_gv * 1.25
        return (x0 - r, x0 + r, y0 - r, y0 + r)
    xmin, xmax, ymin, ymax = box
    m = 0.15 * max(xmax - xmin, ymax - ymin, 1.0)
    m = min(m, 1.0 + 0.1 * min(xmax - xmin, ymax - ymin))
    return (xmin - m, xmax + m, ymin - m, ymax + m)


def demo_figure(story: Any, path: Path) -> Path:
    """The demo's picture: the kidnapped robot, plain AMCL, the poses the laser leaves symloc
    (with the visual map's keyframes), symloc's path and pose, the image that decided, and the
    paper's path alone (the drive to the centre) from the same start.

    Map panels show the room (axes in metres, each with a legend); a long room (a corridor
    more than three times longer than wide) gets one full-width row per panel, so it is not
    drawn as a thin line in a blank square.
    """
    plt = _plt()
    view = _view(story)
    width, height = view[1] - view[0], view[3] - view[2]
    long_room = max(width, height) > 3.0 * min(width, height)
    paper = getattr(story, "paper_path", None) is not None
    images = story.query_image is not None or story.matched_image is not None or paper
    if long_room:
        # one full-width row per map panel, as tall as the room's outline needs
        row = 0.7 + 13.5 * min(width, height) / max(width, height)
        rows = [row] * 4 + ([4.0] if images else [])
        fig = plt.figure(figsize=(15, sum(rows) + 0.8))
        gs = fig.add_gridspec(len(rows), 2, height_ratios=rows)
        slots = [gs[0, :], gs[1, :], gs[2, :], gs[3, :]]
        if images:
            slots += [gs[4, 0], gs[4, 1]]
    else:
        fig = plt.figure(figsize=(15, 8.5))
        gs = fig.add_gridspec(2, 4)
        slots = [gs[0, 0], gs[0, 1], gs[0, 2], gs[0, 3], gs[1, 0:2], gs[1, 2:4]]
    grid = story.grid
    ext = grid.extent()
    img = np.where(grid.data < 0, 0.75, 1.0 - grid.data / 100.0)
    arrow_len = 0.08 * min(max(width, height), 6.0)

    def map_axes(ax: Any, title: str) -> None:
        ax.imshow(img, cmap="gray", origin="lower", extent=ext, vmin=0, vmax=1)
        ax.set_title(title, fontsize=10)
        ax.set_xlim(view[0], view[1])
        ax.set_ylim(view[2], view[3])
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]", fontsize=8)
        ax.set_ylabel("y [m]", fontsize=8)
        ax.tick_params(labelsize=7)

    def arrow(ax: Any, pose: Any, color: str, label: str) -> None:
        ax.arrow(
            pose[0],
            pose[1],
            arrow_len * np.cos(pose[2]),
            arrow_len * np.sin(pose[2]),
            width=0.085 * arrow_len,
            color=color,
            length_includes_head=True,
            label=label or None,
        )

    def legend(ax: Any) -> None:
        ax.legend(fontsize=7, loc="lower left", markerscale=6, framealpha=0.85)

    ax = fig.add_subplot(slots[0])
    map_axes(ax, "map, kidnapped robot")
    arrow(ax, story.kidnap_pose, "g", "true pose")
    legend(ax)

    ax = fig.add_subplot(slots[1])
    map_axes(ax, f"plain AMCL (nav2's filter)\n{story.amcl_summary}")
    p = story.amcl_particles
    apath = getattr(story, "amcl_path", None)
    if apath is not None and len(apath) > 1:
        ax.plot(apath[:, 0], apath[:, 1], color="tab:olive", lw=0.6, alpha=0.7, label="drive")
    ax.scatter(p[:, 0], p[:, 1], s=1, c="tab:blue", alpha=0.3, label="AMCL particles")
    arrow(ax, story.amcl_true_pose, "g", "true pose")
    if story.amcl_estimate is not None:
        arrow(ax, story.amcl_estimate, "r", "AMCL estimate")
    legend(ax)

    ax = fig.add_subplot(slots[2])
    k = len(story.candidates)
    map_axes(ax, f"symloc: {k} poses fit the scan;\nthe camera checks them on keyframes")
    p = story.particles_before
    if p is not None:
        ax.scatter(
            p[:, 0], p[:, 1], s=1, c="tab:orange", alpha=0.3, label="AMCL before the decision"
        )
    kf = getattr(story, "keyframes", None)
    if kf is not None and len(kf):
        ax.quiver(
            kf[:, 0],
            kf[:, 1],
            np.cos(kf[:, 2]),
            np.sin(kf[:, 2]),
            color="tab:cyan",
            scale=25,
            width=0.006,
            label=f"{len(kf)} keyframes (mapping trip)",
        )
    for i, h in enumerate(story.candidates):
        arrow(ax, h, "m", f"the {k} poses the scan fits" if i == 0 else "")
    arrow(ax, story.kidnap_pose, "g", "true pose")
    legend(ax)

    ax = fig.add_subplot(slots[3])
    map_axes(ax, f"symloc: path and pose\n({story.symloc_summary})")
    path_xy = np.asarray(story.path)
    ax.plot(path_xy[:, 0], path_xy[:, 1], "g-", lw=1.5, label="true path")
    p = story.particles_after
    if p is not None:
        ax.scatter(p[:, 0], p[:, 1], s=1, c="tab:blue", alpha=0.3, label="AMCL particles")
    if story.final_pose is not None:
        arrow(ax, story.final_pose, "r", "symloc pose")
    arrow(ax, path_xy[-1], "g", "true pose")
    legend(ax)

    if len(slots) > 4:
        ax = fig.add_subplot(slots[4])
        shown = story.query_image if story.matched_image is None else story.matched_image
        if shown is not None:
            ax.imshow(shown)
        ax.set_title(
            story.match_label
            if story.matched_image is not None
            else f"camera: {story.match_label}",
            fontsize=10,
        )
        ax.axis("off")
        ax = fig.add_subplot(slots[5])
        if paper:
            map_axes(ax, f"the paper's path alone (drive to the centre): {story.paper_summary}")
            pp = np.asarray(story.paper_path)
            ax.plot(pp[:, 0], pp[:, 1], "g-", lw=1.5, label="true path to the centre")
            if story.paper_final is not None:
                arrow(ax, story.paper_final, "r", "its pose")
            arrow(ax, pp[-1], "g", "true pose")
            legend(ax)
        else:
            if story.query_image is not None:
                ax.imshow(story.query_image)
            ax.set_title("query image", fontsize=10)
            ax.axis("off")
    fig.suptitle(story.title)
    fig.tight_layout()
    return save_figure(fig, path, dpi=72)


def localization_figure(rows: Sequence[dict[str, Any]], path: Path) -> Path:
    """Bars: correct / confident wrong / undetermined per room, plain AMCL vs symloc."""
    plt = _plt()
    labels = sorted(
        {(r["room"], r["lab"]) for r in rows},
        key=lambda rl: rows.index(next(r for r in rows if (r["room"], r["lab"]) == rl)),
    )
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5), sharey=True)
    x = np.arange(len(labels))
    for ax, method in zip(axes, ("amcl", "symloc"), strict=True):

        def share(key: str, m: str = method) -> Any:
            vals = []
            for room, labk in labels:
                r = next(
                    (
                        r
                        for r in rows
                        if r["room"] == room and r["lab"] == labk and r["method"] == m
                    ),
                    None,
                )
                vals.append(0.0 if r is None else r.get(key, 0) / max(r["trials"], 1))
            return np.array(vals)

        c, w, u = share("correct"), share("confident_wrong"), share("undetermined")
        ax.bar(x, c, color="tab:green", label="correct")
        ax.bar(x, w, bottom=c, color="tab:red", label="confident wrong")
        ax.bar(x, u, bottom=c + w, color="tab:gray", label="undetermined")
        near = share("undetermined_estimate_on_wrong_copy")
        ax.bar(
            x,
            near,
            bottom=c + w,
            color="none",
            edgecolor="tab:orange",
            hatch="//",
            label="  of which the estimate sits on a wrong copy",
        )
        ax.set_xticks(x, [f"{r}\n{lab}" for r, lab in labels], fontsize=8)
        ax.set_title("plain AMCL" if method == "amcl" else "symloc")
        ax.set_ylim(0, 1.05)
    axes[0].set_ylabel("share of kidnapped-robot trials")
    handles, labels_ = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels_, loc="lower center", ncol=4, fontsize=8)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return save_figure(fig, path, dpi=110)
