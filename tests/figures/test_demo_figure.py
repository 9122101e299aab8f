"""The demo's picture: every map panel has a legend and metre axes; a 40 m corridor fills it;
the keyframes and the paper's path are drawn when the story has them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from symloc.bench.demo import DemoStory
from symloc.grid import OccupancyGrid


def _story(box: tuple[float, float, float, float], images: bool, paper: bool) -> DemoStory:
    xmin, xmax, ymin, ymax = box
    res = 0.1
    w, h = int((xmax - xmin + 2) / res), int((ymax - ymin + 2) / res)
    data = np.zeros((h, w), np.int8)
    data[[0, -1], :] = 100
    data[:, [0, -1]] = 100
    grid = OccupancyGrid(data, res, np.array([xmin - 1, ymin - 1, 0.0]))
    c = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2])
    rng = np.random.default_rng(0)
    parts = np.column_stack([rng.normal(c[0], 0.3, 200), rng.normal(c[1], 0.3, 200), np.zeros(200)])
    img = np.zeros((48, 64, 3), np.uint8) if images else None
    return DemoStory(
        title="t",
        grid=grid,
        room_center=c,
        room_gv=float(np.hypot(xmax - xmin, ymax - ymin) / 2),
        kidnap_pose=np.array([c[0], c[1], 0.3]),
        amcl_particles=parts,
        amcl_true_pose=np.array([c[0], c[1], 0.3]),
        amcl_estimate=np.array([c[0] + 1, c[1], 0.3]),
        amcl_summary="s",
        particles_before=parts,
        candidates=[np.array([c[0], c[1], a]) for a in (0.0, 1.57, 3.14, -1.57)],
        path=np.array([[c[0], c[1], 0.0], [c[0] + 0.5, c[1], 0.0]]),
        particles_after=parts,
        final_pose=np.array([c[0] + 0.5, c[1], 0.0]),
        symloc_summary="tracking",
        query_image=img,
        matched_image=img,
        match_label="place 1, direction 4 of 4",
        room_box=box,
        keyframes=np.array([[c[0], c[1], 0.0], [c[0] + 0.2, c[1], 1.0]]) if paper else None,
        paper_path=np.array([[c[0], c[1], 0.0], [c[0] + 0.3, c[1], 0.0]]) if paper else None,
        paper_final=np.array([c[0] + 0.3, c[1], 0.0]) if paper else None,
        paper_summary="correct after 0.30 m / 5.0 s",
    )


@pytest.mark.parametrize(
    ("box", "images", "long_room", "paper"),
    [
        ((-1.5, 1.5, -1.5, 1.5), True, False, True),
        ((-1.5, 1.5, -1.5, 1.5), True, False, False),
        ((-20.0, 20.0, -1.0, 1.0), False, True, False),
    ],
)
def test_demo_figure_panels(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    box: tuple[float, float, float, float],
    images: bool,
    long_room: bool,
    paper: bool,
) -> None:
    import symloc.figures.demo as fd

    figs: list[Any] = []

    def keep(fig: Any, path: Path, **kw: Any) -> Path:
        figs.append(fig)
        fig.savefig(path, dpi=40)
        return path

    monkeypatch.setattr(fd, "save_figure", keep)
    out = fd.demo_figure(_story(box, images, paper), tmp_path / "d.png")
    assert out.stat().st_size > 1000
    fig = figs[0]
    maps = [ax for ax in fig.axes if ax.get_xlabel() == "x [m]"]
    assert len(maps) == 4 + paper
    for ax in maps:
        assert ax.get_ylabel() == "y [m]"
        assert ax.get_legend() is not None
    labels = [t.get_text() for t in maps[2].get_legend().get_texts()]
    assert "the 4 poses the scan fits" in labels
    assert "AMCL before the decision" in labels
    assert ("2 keyframes (mapping trip)" in labels) is paper
    assert len(fig.axes) == 4 + (2 if images or paper else 0)
    if paper:
        assert maps[4].get_title().startswith("the paper's path alone")
    if long_room:  # full-width panels: the corridor is not a line in a blank square
        width = fig.get_size_inches()[0]
        for ax in maps:
            bbox = ax.get_position()
            assert bbox.width > 0.8
            assert (bbox.height * fig.get_size_inches()[1]) / (bbox.width * width) < 0.2
