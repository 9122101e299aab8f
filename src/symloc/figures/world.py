"""Figures of the simulated world: top view (walls, robot, lidar points) and the camera image."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.figures._save import save_figure

__all__ = ["plot_world", "scene_figure"]


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_world(ax: Any, world: Any, *, lidar_height: float | None = None) -> None:
    """Draw a :class:`~symloc.sim.world.World` seen from above on a matplotlib axis.

    Walls are coloured by material (boards tan, plain walls grey, photographed walls dark
    blue, furniture brown, glass light blue, dark surfaces black, people orange); primitives no
    taller than ``lidar_height`` [m] are dashed (the lidar does not see them).
    """
    from symloc.sim.world import (
        MATERIAL_BOARD,
        MATERIAL_DARK,
        MATERIAL_FURNITURE,
        MATERIAL_GLASS,
        MATERIAL_PERSON,
        MATERIAL_PHOTO,
    )

    plain = {
        MATERIAL_BOARD: "tan",
        MATERIAL_FURNITURE: "saddlebrown",
        MATERIAL_GLASS: "deepskyblue",
        MATERIAL_DARK: "black",
        MATERIAL_PERSON: "darkorange",
    }

    def color(m: int) -> str:
        if m >= MATERIAL_PHOTO:
            return "navy"
        return plain.get(m, "0.45")

    for seg, h, m in zip(world.walls, world.wall_heights, world.wall_materials, strict=True):
        low = lidar_height is not None and h <= lidar_height
        ax.plot(
            [seg[0], seg[2]],
            [seg[1], seg[3]],
            "--" if low else "-",
            color=color(int(m)),
            lw=2.5 if m >= MATERIAL_PHOTO else 2.0,
            solid_capstyle="round",
        )
    for (cx, cy, r), h, m in zip(
        world.circles, world.circle_heights, world.circle_materials, strict=True
    ):
        low = lidar_height is not None and h <= lidar_height
        ax.add_patch(
            _circle_patch((cx, cy), r, color(int(m)), "--" if low else "-"),
        )


def _circle_patch(center: tuple[float, float], r: float, col: str, ls: str) -> Any:
    from matplotlib.patches import Circle

    return Circle(center, r, fill=False, ec=col, lw=2.0, ls=ls)


def scene_figure(
    world: Any,
    pose: ArrayLike,
    points_world: NDArray[np.float64],
    image: NDArray[np.uint8],
    path: Path,
    *,
    hfov: float | None = None,
    robot_radius: float = 0.177,
    lidar_height: float | None = None,
    title: str | None = None,
) -> Path:
    """Top view of the world with the robot and its lidar points, beside the camera image.

    Parameters
    ----------
    world : World
    pose : array of shape (3,)
        Robot pose x [m], y [m], theta [rad].
    points_world : ndarray of shape (M, 2)
        Lidar points in the world frame [m].
    image : ndarray of shape (H, W, 3)
        The camera image (RGB uint8).
    path : Path
        Where to write the PNG.
    hfov : float, optional
        Camera horizontal field of view [rad], drawn as a wedge.
    """
    plt = _plt()
    p = np.asarray(pose, dtype=np.float64)
    fig, (ax, ax_img) = plt.subplots(
        1, 2, figsize=(13.0, 5.6), gridspec_kw={"width_ratios": [1.0, 1.25]}
    )
    plot_world(ax, world, lidar_height=lidar_height)
    if points_world.size:
        ax.plot(points_world[:, 0], points_world[:, 1], ".", color="red", ms=2.5, label="lidar")
    from matplotlib.patches import Circle, Wedge

    ax.add_patch(Circle((p[0], p[1]), robot_radius, fc="limegreen", ec="k", lw=1.0, zorder=5))
    ax.annotate(
        "",
        xy=(p[0] + 0.45 * math.cos(p[2]), p[1] + 0.45 * math.sin(p[2])),
        xytext=(p[0], p[1]),
        arrowprops={"arrowstyle": "->", "lw": 1.8},
        zorder=6,
    )
    if hfov is not None:
        half = math.degrees(hfov / 2)
        deg = math.degrees(p[2])
        ax.add_patch(
            Wedge((p[0], p[1]), 1.2, deg - half, deg + half, fc="gold", alpha=0.3, zorder=4)
        )
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("top view: walls (navy = photo, tan = board, dashed = below lidar)")
    if points_world.size:
        ax.legend(loc="upper right", fontsize=8)
    ax_img.imshow(image)
    ax_img.set_title(f"camera {image.shape[1]} x {image.shape[0]}")
    ax_img.axis("off")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)
