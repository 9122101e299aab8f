"""Figures for the mcl experiments (the only mcl code that imports matplotlib)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symloc.figures._save import save_figure

__all__ = [
    "amcl_carmen_figure",
    "amcl_global_confidence_figure",
    "amcl_symmetric_figure",
    "draw_amcl_state",
]


def _arrow(ax: Any, pose: np.ndarray, color: str, label: str, length: float = 0.5) -> None:
    ax.annotate(
        "",
        xy=(pose[0] + length * np.cos(pose[2]), pose[1] + length * np.sin(pose[2])),
        xytext=(pose[0], pose[1]),
        arrowprops={"arrowstyle": "-|>", "color": color, "lw": 2.0},
    )
    ax.plot(pose[0], pose[1], "o", color=color, ms=6, label=label)


def draw_amcl_state(
    ax: Any,
    grid: Any,
    particles: np.ndarray,
    *,
    true_pose: np.ndarray | None = None,
    estimate: np.ndarray | None = None,
    max_particles: int = 3000,
) -> None:
    """Map, particles (with heading ticks), true pose and estimate on one axes."""
    img = np.where(grid.data < 0, 0.5, 1.0 - grid.data / 100.0)
    ax.imshow(img, cmap="gray", origin="lower", extent=grid.extent(), vmin=0, vmax=1)
    p = particles[:: max(1, len(particles) // max_particles)]
    ax.quiver(
        p[:, 0],
        p[:, 1],
        np.cos(p[:, 2]),
        np.sin(p[:, 2]),
        color="tab:red",
        alpha=0.5,
        scale=40,
        width=0.003,
        headwidth=2,
    )
    if true_pose is not None:
        _arrow(ax, true_pose, "tab:green", "true pose")
    if estimate is not None:
        _arrow(ax, estimate, "tab:blue", "AMCL estimate")
    ax.set_aspect("equal")


def amcl_symmetric_figure(
    summaries: Sequence[Mapping[str, Any]],
    examples: Mapping[str, tuple[Any, Any]],
    path: Path,
) -> Path:
    """Figure-8-like panels (one example per room) and a bar chart of the outcome rates."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(summaries)
    fig, axes = plt.subplots(1, n + 1, figsize=(4.2 * (n + 1), 4.4))
    axes = np.atleast_1d(axes)
    for ax, s in zip(axes[:n], summaries, strict=True):
        grid, t = examples[s["room"]]
        draw_amcl_state(ax, grid, t.particles, true_pose=t.true_pose, estimate=t.estimate)
        ax.set_title(
            f"{s['room']} (k={s['order']}): {t.outcome.replace('_', ' ')}\n"
            f"reported std {t.std_xy:.2f} m / {np.degrees(t.std_theta):.1f} deg",
            fontsize=9,
        )
        ax.legend(loc="lower right", fontsize=7)
    ax = axes[n]
    names = [s["room"] for s in summaries]
    x = np.arange(n)
    tot = np.array([max(s["trials"], 1) for s in summaries], dtype=float)
    corr = np.array([s["correct"] for s in summaries]) / tot
    sym = np.array([s["symmetric_copy"] for s in summaries]) / tot
    nc = np.array([s["not_converged"] for s in summaries]) / tot
    cw = np.array([s["confident_wrong"] for s in summaries]) / tot
    # Confident & wrong under weaker definitions (symloc.mcl.confidence without the rival
    # search; the old covariance-only test), when the summaries carry them.
    extra = [
        (key, label, color)
        for key, label, color in (
            ("confident_wrong_without_rival_check", "conf. & wrong, no rival check", "tab:pink"),
            ("confident_wrong_covariance_only", "conf. & wrong, covariance only", "tab:gray"),
        )
        if all(key in s for s in summaries)
    ]
    nb = 4 + len(extra)
    wb = 0.8 / nb
    off = (np.arange(nb) - (nb - 1) / 2.0) * wb
    ax.bar(x + off[0], corr, wb, label="correct")
    ax.bar(x + off[1], sym, wb, label="symmetric copy")
    ax.bar(x + off[2], nc, wb, label="not converged")
    ax.bar(x + off[3], cw, wb, label="confident & wrong", color="tab:red")
    for j, (key, label, color) in enumerate(extra):
        v = np.array([s[key] for s in summaries]) / tot
        ax.bar(x + off[4 + j], v, wb, label=label, color=color)
    ax.plot(
        x + off[0], [s["expected_correct_rate"] for s in summaries], "k_", ms=12, mew=2, label="1/k"
    )
    ax.set_xticks(x, names)
    ax.set_ylim(0, 1)
    ax.set_ylabel("fraction of trials")
    ax.set_title(f"plain AMCL, uniform start ({int(tot[0])} trials/room)", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def amcl_carmen_figure(
    logs: Sequence[Mapping[str, Any]],
    path: Path,
) -> Path:
    """Per log: the map with corrected and AMCL trajectories, and the tracking error over time.

    Each entry holds ``name``, ``grid``, ``truth (T, 3)``, ``estimate (T, 3)``, ``stamps (T,)``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(logs)
    fig, axes = plt.subplots(2, n, figsize=(5.0 * n, 8.5), squeeze=False)
    for i, lg in enumerate(logs):
        ax = axes[0, i]
        g = lg["grid"]
        img = np.where(g.data < 0, 0.5, 1.0 - g.data / 100.0)
        ax.imshow(img, cmap="gray", origin="lower", extent=g.extent(), vmin=0, vmax=1)
        ax.plot(lg["truth"][:, 0], lg["truth"][:, 1], "g-", lw=1, label="corrected poses")
        ax.plot(lg["estimate"][:, 0], lg["estimate"][:, 1], "r-", lw=0.8, label="AMCL")
        ax.set_title(lg["name"])
        ax.legend(fontsize=7)
        ax.set_aspect("equal")
        ax = axes[1, i]
        err = np.hypot(*(lg["estimate"][:, :2] - lg["truth"][:, :2]).T)
        dth = np.abs(np.pi - np.mod(np.pi - (lg["estimate"][:, 2] - lg["truth"][:, 2]), 2 * np.pi))
        t = lg["stamps"] - lg["stamps"][0]
        ax.plot(t, err, "b-", lw=0.8, label="position error [m]")
        ax2 = ax.twinx()
        ax2.plot(t, np.degrees(dth), "r-", lw=0.5, alpha=0.6)
        ax2.set_ylabel("heading error [deg]", color="r")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("position error [m]", color="b")
        ax.set_title(f"tracking: mean {err.mean():.3f} m, {np.degrees(dth).mean():.2f} deg")
    fig.tight_layout()
    return save_figure(fig, path, dpi=100)


def amcl_global_confidence_figure(
    logs: Sequence[Mapping[str, Any]],
    path: Path,
) -> Path:
    """Global localization from random starts: position error per scan, confident scans bold.

    Each entry holds ``name`` and ``trace``: a list of runs, each with ``dxy (S,)`` [m] and
    ``confident (S,)`` and ``confident_covariance_only (S,)`` bool arrays.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(logs)
    fig, axes = plt.subplots(2, n, figsize=(5.0 * n, 7.5), squeeze=False, sharey=True)
    for i, lg in enumerate(logs):
        for row, key, title in (
            (0, "confident", "symloc confidence"),
            (1, "confident_covariance_only", "old: 1 hypothesis, std < 0.3 m / 15 deg"),
        ):
            ax = axes[row, i]
            n_bad = 0
            for run in lg["trace"]:
                e = np.maximum(np.asarray(run["dxy"]), 1e-3)
                c = np.asarray(run[key], dtype=bool)
                k = np.arange(e.size)
                ax.plot(k, e, "-", color="0.7", lw=0.6)
                wrong = c & (e > 1.0)
                n_bad += int(wrong.any())
                ax.plot(k, np.where(c & ~wrong, e, np.nan), "-", color="tab:blue", lw=2.0)
                ax.plot(k, np.where(wrong, e, np.nan), "-", color="tab:red", lw=2.0)
            ax.axhline(1.0, color="k", ls="--", lw=0.8)
            ax.axhline(0.3, color="k", ls=":", lw=0.8)
            ax.set_yscale("log")
            ax.set_title(f"{lg['name']}: {title}\n{n_bad} runs confident > 1 m off", fontsize=9)
            ax.set_xlabel("scans since the uniform start")
            if i == 0:
                ax.set_ylabel("position error [m] (bold: confident; red: > 1 m off)")
    fig.tight_layout()
    return save_figure(fig, path, dpi=100)
