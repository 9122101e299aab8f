"""The demo's picture: every map panel has a legend and metre axes; a 40 m corridor fills it;
the keyframes and the paper's path are drawn when the story has them; the camera's check names
each pose with its inliers and rings the chosen one; the final pose has an inset with its error;
the three verdicts are tabled."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from symloc.bench.demo import CameraCheck, DemoStory
from symloc.grid import OccupancyGrid


def _story(
    box: tuple[float, float, float, float], images: bool, paper: bool, check: bool = True
) -> DemoStory:
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
        check=CameraCheck(
            poses=np.array([[c[0], c[1], a] for a in (0.0, 1.57, 3.14, -1.57)]),
            inliers=np.array([3, 122, 7, 0]),
            verdicts=["contradicted", "verified", "contradicted", "unknown"],
            chosen=1,
            min_inliers=25,
            true_pose=np.array([c[0], c[1], 1.6]),
        )
        if check
        else None,
        symloc_error=(0.035, 0.004),
        summary=[
            ("plain AMCL", "confident wrong", "75.9 cm, 178°", "9.1 m, 45 s"),
            ("symloc", "correct", "3.5 cm, 0°", "0.00 m, 0.0 s"),
        ],
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
    story = _story(box, images, paper)
    c = float(story.path[-1][0])
    out = fd.demo_figure(story, tmp_path / "d.png")
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
    # the map panels, the image, the scores and the summary
    assert len(fig.axes) == len(maps) + 3
    texts = [t.get_text() for t in maps[2].texts]
    assert texts == ["1: 3", "2: 122", "3: 7", "4: 0"]
    ringed = [ln for ln in maps[2].lines if ln.get_markeredgecolor() == "gold"]
    assert len(ringed) == 1
    assert ringed[0].get_xydata()[0] == pytest.approx(maps[2].texts[1].xy)
    inset = maps[3].child_axes  # +-15 cm around the true final pose
    assert len(inset) == 1
    assert inset[0].get_xlim() == pytest.approx((c - 0.15, c + 0.15))
    assert any("error 3.5 cm, 0.2 deg" in t.get_text() for t in inset[0].texts)
    scores = next(ax for ax in fig.axes if ax.get_title().startswith("the camera's check"))
    assert len(scores.patches) == 4
    assert scores.get_title().endswith("pose 2 chosen")
    table = next(ax for ax in fig.axes if ax.tables)
    cells = table.tables[0].get_celld()
    assert cells[1, 1].get_text().get_text() == "confident wrong"
    if paper:
        assert maps[4].get_title().startswith("the paper's path alone")
    if long_room:  # full-width panels: the corridor is not a line in a blank square
        width = fig.get_size_inches()[0]
        for ax in maps:
            bbox = ax.get_position()
            assert bbox.width > 0.8
            assert (bbox.height * fig.get_size_inches()[1]) / (bbox.width * width) < 0.2


def test_demo_figure_without_camera_check(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Decided at the centre (the paper's path) or not at all: the poses are numbered without
    scores, none is ringed, and the scores panel says the camera checked none."""
    import symloc.figures.demo as fd

    figs: list[Any] = []
    monkeypatch.setattr(fd, "save_figure", lambda fig, path, **kw: figs.append(fig) or path)
    fd.demo_figure(_story((-1.5, 1.5, -1.5, 1.5), True, True, check=False), tmp_path / "d.png")
    fig = figs[0]
    maps = [ax for ax in fig.axes if ax.get_xlabel() == "x [m]"]
    assert [t.get_text() for t in maps[2].texts] == ["1", "2", "3", "4"]
    assert not [ln for ln in maps[2].lines if ln.get_markeredgecolor() == "gold"]
    assert any("checked no hypotheses" in t.get_text() for ax in fig.axes for t in ax.texts)
