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


#: most AMCL particles drawn per panel: enough to show the clouds, few enough to leave the
#: poses on top of them readable
_MAX_PARTICLES = 1500
_GRADE_COLOURS = {"correct": "tab:green", "confident wrong": "tab:red"}  # by summary verdict


def _thin(p: Any) -> Any:
    """At most :data:`_MAX_PARTICLES` rows of ``p`` (N, >=2), evenly spaced."""
    p = np.asarray(p)
    return p if len(p) <= _MAX_PARTICLES else p[:: int(np.ceil(len(p) / _MAX_PARTICLES))]


def demo_figure(story: Any, path: Path) -> Path:
    """The demo's picture, one story from left to right and top to bottom.

    Top row (maps): the kidnapped robot; plain AMCL after its drive (its estimate red);
    the poses the scan fits, numbered, each with the camera's inliers and the one chosen
    ringed; symloc's path and pose with an inset of the final pose and its error. Bottom row:
    the image the camera decided from, the inliers of every hypothesis against the fewest
    that verify, the paper's path alone (the drive to the centre), and the three verdicts.

    Map panels show the room (axes in metres, each with a legend); a long room (a corridor
    more than three times longer than wide) gets one full-width row per map, so it is not
    drawn as a thin line in a blank square.
    """
    plt = _plt()
    view = _view(story)
    width, height = view[1] - view[0], view[3] - view[2]
    long_room = max(width, height) > 3.0 * min(width, height)
    paper = getattr(story, "paper_path", None) is not None
    n_maps = 4 + paper
    if long_room:
        row = 0.7 + 13.5 * min(width, height) / max(width, height)
        rows = [row] * n_maps + [4.0]
        fig = plt.figure(figsize=(15, sum(rows) + 0.8))
        gs = fig.add_gridspec(len(rows), 3, height_ratios=rows)
        slots = [gs[i, :] for i in range(n_maps)]
        image_slot, bars_slot, summary_slot = gs[n_maps, 0], gs[n_maps, 1], gs[n_maps, 2]
    else:
        fig = plt.figure(figsize=(16, 8.5))
        gs = fig.add_gridspec(2, 4)
        slots = [gs[0, 0], gs[0, 1], gs[0, 2], gs[0, 3]] + ([gs[1, 2]] if paper else [])
        image_slot, bars_slot, summary_slot = gs[1, 0], gs[1, 1], gs[1, 3 if paper else 2]
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

    def arrow(ax: Any, pose: Any, color: str, label: str, scale: float = 1.0) -> None:
        n = arrow_len * scale
        ax.arrow(
            pose[0],
            pose[1],
            n * np.cos(pose[2]),
            n * np.sin(pose[2]),
            width=0.085 * n,
            color=color,
            length_includes_head=True,
            label=label or None,
            zorder=4,
        )

    def particles(ax: Any, p: Any, colour: str, label: str) -> None:
        q = _thin(p)
        ax.scatter(q[:, 0], q[:, 1], s=1, c=colour, alpha=0.2, label=label, zorder=2)

    def legend(ax: Any) -> None:
        ax.legend(fontsize=7, loc="lower left", markerscale=6, framealpha=0.85)

    ax = fig.add_subplot(slots[0])
    map_axes(ax, "map, kidnapped robot")
    arrow(ax, story.kidnap_pose, "g", "true pose")
    legend(ax)

    ax = fig.add_subplot(slots[1])
    map_axes(ax, f"plain AMCL (nav2's filter)\n{story.amcl_summary}")
    apath = getattr(story, "amcl_path", None)
    if apath is not None and len(apath) > 1:
        ax.plot(apath[:, 0], apath[:, 1], color="tab:olive", lw=0.6, alpha=0.7, label="drive")
    particles(ax, story.amcl_particles, "tab:blue", "AMCL particles")
    arrow(ax, story.amcl_true_pose, "g", "true pose after the drive")
    if story.amcl_estimate is not None:
        arrow(ax, story.amcl_estimate, "r", "AMCL estimate")
    legend(ax)

    _candidates_panel(fig.add_subplot(slots[2]), story, map_axes, arrow, particles, legend)

    ax = fig.add_subplot(slots[3])
    map_axes(ax, f"symloc: path and pose\n({story.symloc_summary})")
    path_xy = np.asarray(story.path)
    ax.plot(path_xy[:, 0], path_xy[:, 1], "g-", lw=1.5, label="true path")
    if story.particles_after is not None:
        particles(ax, story.particles_after, "tab:blue", "AMCL particles")
    if story.final_pose is not None:
        arrow(ax, story.final_pose, "r", "symloc pose")
    arrow(ax, path_xy[-1], "g", "true pose")
    legend(ax)
    if story.final_pose is not None:
        _final_inset(ax, story, path_xy[-1])

    if paper:
        ax = fig.add_subplot(slots[4])
        map_axes(ax, f"the paper's path alone (drive to the centre):\n{story.paper_summary}")
        pp = np.asarray(story.paper_path)
        ax.plot(pp[:, 0], pp[:, 1], "g-", lw=1.5, label="true path to the centre")
        if story.paper_final is not None:
            arrow(ax, story.paper_final, "r", "its pose")
        arrow(ax, pp[-1], "g", "true pose")
        legend(ax)

    ax = fig.add_subplot(image_slot)
    shown = story.query_image if story.matched_image is None else story.matched_image
    if shown is not None:
        ax.imshow(shown)
    else:
        ax.text(0.5, 0.5, "no image", ha="center", va="center", transform=ax.transAxes)
    label = story.match_label if story.matched_image is not None else f"camera: {story.match_label}"
    ax.set_title(label, fontsize=10)
    ax.axis("off")
    _scores_panel(fig.add_subplot(bars_slot), story)
    _summary_panel(fig.add_subplot(summary_slot), story)
    fig.suptitle(story.title)
    fig.tight_layout()
    return save_figure(fig, path, dpi=72)


def _candidates_panel(
    ax: Any, story: Any, map_axes: Any, arrow: Any, particles: Any, legend: Any
) -> None:
    """The poses the scan fits, numbered as in the scores panel; the chosen one ringed."""
    check = getattr(story, "check", None)
    if check is not None:
        poses, truth = check.poses, check.true_pose
        title = f"symloc: {len(poses)} poses fit the scan;\nthe camera checks each on keyframes"
    else:
        poses, truth = np.asarray(story.candidates).reshape(-1, 3), story.kidnap_pose
        title = f"symloc: {len(poses)} poses fit the scan"
    map_axes(ax, title)
    if story.particles_before is not None:
        particles(ax, story.particles_before, "tab:orange", "AMCL before the decision")
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
            zorder=3,
        )
    x0, x1 = ax.get_xlim()
    off = 0.06 * (x1 - x0)
    for i, h in enumerate(poses):
        chosen = check is not None and check.chosen == i
        arrow(ax, h, "m", f"the {len(poses)} poses the scan fits" if i == 0 else "")
        text = f"{i + 1}" + (f": {check.inliers[i]}" if check is not None else "")
        ax.annotate(
            text,
            (h[0], h[1]),
            xytext=(h[0] - off * np.cos(h[2]), h[1] - off * np.sin(h[2])),
            fontsize=8,
            ha="center",
            va="center",
            color="k",
            fontweight="bold" if chosen else "normal",
            bbox={"boxstyle": "round,pad=0.15", "fc": "gold" if chosen else "w", "alpha": 0.85},
            zorder=6,
        )
        if chosen:
            ax.plot(
                h[0],
                h[1],
                "o",
                ms=16,
                mfc="none",
                mec="gold",
                mew=2.5,
                zorder=5,
            )
    if truth is not None:
        arrow(ax, truth, "g", "true pose", scale=0.8)
    legend(ax)


def _final_inset(ax: Any, story: Any, truth: Any) -> None:
    """An inset of +-15 cm around the true final pose: symloc's pose and its error."""
    r = 0.15
    ins = ax.inset_axes((0.58, 0.58, 0.4, 0.4))
    ins.set_xlim(truth[0] - r, truth[0] + r)
    ins.set_ylim(truth[1] - r, truth[1] + r)
    ins.set_aspect("equal")
    ins.set_xticks([])
    ins.set_yticks([])
    for pose, colour in ((truth, "g"), (story.final_pose, "r")):
        ins.arrow(
            pose[0],
            pose[1],
            0.08 * np.cos(pose[2]),
            0.08 * np.sin(pose[2]),
            width=0.006,
            color=colour,
            length_includes_head=True,
        )
    ins.plot([truth[0] - 0.05, truth[0] + 0.05], [truth[1] - r + 0.02] * 2, "k-", lw=2)
    ins.text(truth[0], truth[1] - r + 0.03, "10 cm", ha="center", fontsize=6)
    err = getattr(story, "symloc_error", None)
    if err is not None:
        ins.text(
            0.5,
            0.97,
            f"error {100 * err[0]:.1f} cm, {np.degrees(err[1]):.1f} deg",
            ha="center",
            va="top",
            fontsize=7,
            transform=ins.transAxes,
        )
    ax.indicate_inset_zoom(ins, edgecolor="0.3")


def _scores_panel(ax: Any, story: Any) -> None:
    """The camera's inliers per hypothesis, against the fewest that verify."""
    check = getattr(story, "check", None)
    if check is None or not len(check.inliers):
        ax.axis("off")
        ax.text(
            0.5,
            0.5,
            "the camera checked no hypotheses here\n(" + story.match_label + ")",
            ha="center",
            va="center",
            fontsize=9,
            wrap=True,
            transform=ax.transAxes,
        )
        return
    k = len(check.inliers)
    colours = [
        "gold" if i == check.chosen else ("tab:red" if v == "contradicted" else "0.6")
        for i, v in enumerate(check.verdicts)
    ]
    x = np.arange(1, k + 1)
    ax.bar(x, check.inliers, color=colours, edgecolor="k")
    ax.axhline(
        check.min_inliers,
        color="k",
        ls="--",
        lw=1,
        label=f"fewest that verify ({check.min_inliers})",
    )
    for xi, n, v in zip(x, check.inliers, check.verdicts, strict=True):
        ax.text(xi, n, f"{n}\n{v}", ha="center", va="bottom", fontsize=7)
    ax.set_xticks(x, [f"pose {i}" for i in x], fontsize=8)
    ax.set_ylabel("inliers of the best geometric fit", fontsize=8)
    ax.set_ylim(0, 1.3 * max(int(check.inliers.max()), check.min_inliers) + 1)
    chosen = "none chosen" if check.chosen is None else f"pose {check.chosen + 1} chosen"
    ax.set_title(f"the camera's check of each pose: {chosen}", fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    ax.tick_params(labelsize=7)


def _summary_panel(ax: Any, story: Any) -> None:
    """The three methods' verdicts from the same start, coloured by grade."""
    ax.axis("off")
    rows = getattr(story, "summary", None) or []
    if not rows:
        return
    table = ax.table(
        cellText=[list(r) for r in rows],
        colLabels=["method", "verdict", "error", "travelled"],
        colWidths=[0.22, 0.3, 0.24, 0.24],
        bbox=(-0.05, 0.25, 1.1, 0.5),
        cellLoc="left",
    )
    table.auto_set_font_size(False)
    table.set_fontsize(7.5)
    for i, r in enumerate(rows, start=1):
        table[i, 1].set_facecolor(_GRADE_COLOURS.get(r[1], "0.85"))
        table[i, 1].set_alpha(0.5)
    ax.set_title("from the same kidnapped start", fontsize=10)


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
