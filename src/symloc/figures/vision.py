"""Figures of the vision part: Table 3 (similarity, heading errors) and Figure 14 (keyframes)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symloc.figures._save import save_figure

__all__ = ["keyframes_figure", "matches_figure", "photos_figure", "table3_figure"]


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def table3_figure(result: Any, path: str | Path) -> Path:
    """Similarity matrix heat map and the heading-error histogram of a Table 3 run."""
    plt = _plt()
    d = result.to_dict()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4.2))
    s = np.asarray(d["similarity"])
    im = ax1.imshow(s, cmap="viridis", vmin=0, vmax=max(1e-9, float(s.max())))
    for (i, j), v in np.ndenumerate(s):
        ax1.text(j, i, f"{v:.2f}", ha="center", va="center", color="w" if v < s.max() / 2 else "k")
    ax1.set_xticks(range(4), [f"image {i + 1}" for i in range(4)])
    ax1.set_yticks(range(4), [f"query {i + 1}" for i in range(4)])
    ax1.set_title(f"mean BoW similarity (accuracy {100 * d['accuracy']:.0f} %)")
    fig.colorbar(im, ax=ax1, fraction=0.046)
    err_out = [np.degrees(abs(t.heading_error_out)) for t in result.trials if t.decision.decided]
    err_in = [np.degrees(abs(t.heading_error_in)) for t in result.trials if t.decision.decided]
    bins = np.linspace(0, max([5.0, *err_in]), 26)
    ax2.hist(err_in, bins=bins, alpha=0.6, label="direction only (k x 90 deg)")
    ax2.hist(err_out, bins=bins, alpha=0.8, label="with homography offset")
    ax2.set_xlabel("|heading error| [deg]")
    ax2.set_ylabel("trials")
    u = d["untextured"]
    ax2.set_title(
        f"untextured lab: {u['undetermined']}/{u['trials']} undetermined, {u['wrong']} wrong"
    )
    ax2.legend()
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def keyframes_figure(results: Sequence[Any], path: str | Path) -> Path:
    """Figure 14: stored images against rotation angle, and bytes on disk per policy."""
    plt = _plt()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    theta = np.linspace(0, 360, 721)
    for r in results:
        counts = np.searchsorted(np.sort(r.angles_deg), theta, side="right")
        ax1.step(theta, counts, where="post", label=f"{r.name} ({r.count})")
    ax1.set_xlabel("rotation in place [deg]")
    ax1.set_ylabel("images stored")
    ax1.legend()
    ax1.set_title("one full turn at the centre")
    names = [r.name for r in results]
    x = np.arange(len(results))
    ax2.bar(x - 0.2, [r.bytes_features / 1024 for r in results], 0.4, label="features + BoW")
    ax2.bar(x + 0.2, [r.bytes_with_images / 1024 for r in results], 0.4, label="+ PNG images")
    ax2.set_xticks(x, names, fontsize=8)
    ax2.set_ylabel("database size [KiB]")
    ax2.set_yscale("log")
    ax2.legend()
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def matches_figure(
    query: np.ndarray, stored: Sequence[np.ndarray], path: str | Path, *, lowe_ratio: float = 0.8
) -> Path:
    """The paper's Figure 13: ORB matches of one query against each stored image.

    Each panel draws the matches that pass Lowe's ratio test; the title gives their number and
    the homography (RANSAC) inliers among them.
    """
    import cv2

    from symloc.vision.orb import OrbExtractor
    from symloc.vision.orientation import OrientationConfig, match_homography

    plt = _plt()
    ext = OrbExtractor()
    fq = ext.extract(query)
    kq = [cv2.KeyPoint(float(x), float(y), 8) for x, y in fq.points]
    bf = cv2.BFMatcher(cv2.NORM_HAMMING)
    cfg = OrientationConfig(lowe_ratio=lowe_ratio)
    fig, axes = plt.subplots(len(stored), 1, figsize=(10, 3.6 * len(stored)))
    for i, (ax, img) in enumerate(zip(np.atleast_1d(axes), stored, strict=True)):
        fs = ext.extract(img)
        ks = [cv2.KeyPoint(float(x), float(y), 8) for x, y in fs.points]
        # the same matching as the decision (stored -> query), drawn query -> stored
        knn = bf.knnMatch(fs.descriptors, fq.descriptors, k=2) if min(len(fs), len(fq)) > 1 else []
        good = [
            cv2.DMatch(m[0].trainIdx, m[0].queryIdx, m[0].distance)
            for m in knn
            if len(m) == 2 and m[0].distance < lowe_ratio * m[1].distance
        ]
        _, inl, _ = match_homography(fq, fs, cfg)
        vis = cv2.drawMatches(  # type: ignore[call-overload]
            np.ascontiguousarray(query), kq, np.ascontiguousarray(img), ks, good, None
        )
        ax.imshow(vis)
        ax.set_axis_off()
        ax.set_title(
            f"query (direction 1) vs stored image {i + 1}: {len(good)} ratio-test matches, "
            f"{inl} homography inliers",
            fontsize=9,
        )
    fig.tight_layout()
    return save_figure(fig, path, dpi=90)


def photos_figure(result: Any, path: str | Path, examples: Sequence[tuple[str, Any]] = ()) -> Path:
    """Real-photo experiment: outcome counts per case, heading-offset errors, example queries.

    Parameters
    ----------
    result : symloc.bench.photos.PhotosResult
    path : output PNG
    examples : sequence of (title, (H, W[, 3]) uint8 image)
        Shown in a row under the plots (e.g. the stored views and some re-captures).
    """
    plt = _plt()
    cases = [*result.conditions, *result.ambiguity]
    n_ex = len(examples)
    fig = plt.figure(figsize=(14, 8.0 if n_ex else 4.8), layout="constrained")
    if n_ex:
        top, bottom = fig.subfigures(2, 1, height_ratios=[1.6, 1])
    else:
        top, bottom = fig, None
    ax1, ax2 = top.subplots(1, 2)
    names = [c.case for c in cases]
    y = np.arange(len(cases))
    left = np.zeros(len(cases))
    for key, colour in (
        ("correct", "tab:green"),
        ("undetermined", "tab:orange"),
        ("refused", "tab:gray"),
        ("wrong", "tab:red"),
    ):
        vals = np.array([getattr(c, key) / max(c.trials, 1) for c in cases])
        ax1.barh(y, vals, left=left, color=colour, label=key)
        left += vals
    ax1.set_yticks(y, names)
    ax1.invert_yaxis()
    ax1.axhline(len(result.conditions) - 0.5, color="k", lw=0.8)
    ax1.set_xlabel("fraction of queries")
    ax1.set_title(f"decisions on real photos (yaw up to {result.max_yaw_deg:g} deg)")
    ax1.legend(loc="lower right", fontsize=8)
    data = []
    for c in cases:
        e = [t.heading_error_deg for t in result.trials if t.case == c.case and t.correct]
        data.append(e if e else [np.nan])
    ax2.boxplot(data, orientation="horizontal", tick_labels=names, showfliers=True)
    ax2.invert_yaxis()
    ax2.set_xscale("symlog", linthresh=0.1)
    ax2.set_xlim(left=0.0)
    ax2.set_xlabel("|heading offset - true yaw| [deg] (correct decisions)")
    ax2.set_title("heading-offset error")
    if bottom is not None:
        axes = np.atleast_1d(bottom.subplots(1, n_ex))
        for ax, (title, img) in zip(axes, examples, strict=True):
            ax.imshow(img, cmap="gray" if np.ndim(img) == 2 else None)
            ax.set_title(title, fontsize=8)
            ax.axis("off")
    return save_figure(fig, path, dpi=100)
