"""Figures of the evaluation bench: outcomes per family with Wilson intervals."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symloc.figures._save import save_figure

__all__ = ["outcome_figure"]

_LABELS = {
    "symloc": "symloc (as shipped)",
    "decide": "symloc, deciding where it stands",
    "centre": "symloc, the paper's drive to the centre",
    "amcl": "plain AMCL (nav2's filter alone)",
}


def outcome_figure(
    summary: Sequence[dict[str, Any]], path: Path, *, by: str = "family", title: str = ""
) -> Path:
    """Stacked shares correct / confident wrong / undetermined per group, one panel per method
    (stacked, so that the methods compare group by group), with the confident-wrong rate's
    Wilson 95 % interval as an error bar; each panel's title gives the method's overall rates
    (the ``all`` group) when the summary has them."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = [m for m in _LABELS if any(r["method"] == m for r in summary)]
    groups = list(dict.fromkeys(str(r[by]) for r in summary))
    fig, axes = plt.subplots(
        len(methods),
        1,
        figsize=(max(7.0, 0.6 * len(groups) + 3), 2.4 * len(methods) + 1.4),
        sharex=True,
        sharey=True,
        squeeze=False,
    )
    x = np.arange(len(groups))
    for ax, method in zip(axes[:, 0], methods, strict=True):
        rows = {str(r[by]): r for r in summary if r["method"] == method}

        def share(key: str, rows: dict[str, Any] = rows) -> Any:
            return np.array([rows[g][f"{key}_rate"] if g in rows else 0.0 for g in groups])

        c, w, u = share("correct"), share("confident_wrong"), share("undetermined")
        ax.bar(x, c, color="tab:green", label="correct")
        ax.bar(x, w, bottom=c, color="tab:red", label="confident wrong")
        ax.bar(x, u, bottom=c + w, color="tab:gray", label="undetermined")
        lo = np.array([rows[g]["confident_wrong_ci95"][0] if g in rows else 0.0 for g in groups])
        hi = np.array([rows[g]["confident_wrong_ci95"][1] if g in rows else 0.0 for g in groups])
        ax.errorbar(
            x,
            w,
            yerr=[np.clip(w - lo, 0.0, None), np.clip(hi - w, 0.0, None)],
            fmt="none",
            ecolor="black",
            capsize=3,
            lw=1,
            label="confident wrong: Wilson 95 % interval",
        )
        n = [rows[g]["trials"] if g in rows else 0 for g in groups]
        ax.set_xticks(
            x,
            [f"{g}\nn={k}" for g, k in zip(groups, n, strict=True)],
            fontsize=7,
            rotation=45,
            ha="right",
        )
        overall = rows.get("all")
        ax.set_title(
            _LABELS[method]
            + (
                f": {100 * overall['correct_rate']:.0f} % correct, "
                f"{100 * overall['confident_wrong_rate']:.1f} % confident wrong, "
                f"{100 * overall['undetermined_rate']:.0f} % undetermined"
                if overall is not None
                else ""
            ),
            fontsize=10,
        )
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("share of trials", fontsize=8)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.96 if title else 1))
    return save_figure(fig, path, dpi=110)
