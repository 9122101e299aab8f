from __future__ import annotations

import numpy as np

from symloc.figures.mcl import amcl_global_confidence_figure


def test_global_confidence_figure_writes_a_png(tmp_path):
    run = {
        "dxy": np.array([5.0, 4.0, 0.2, 0.05]),
        "confident": np.array([False, False, True, True]),
        "confident_covariance_only": np.array([False, True, True, True]),
    }
    out = amcl_global_confidence_figure([{"name": "fake", "trace": [run]}], tmp_path / "g.png")
    assert out.is_file()
    assert out.read_bytes()[:4] == b"\x89PNG"


def test_symmetric_figure_with_the_confidence_columns(tmp_path):
    from symloc.experiments.amcl_symmetric import run_room
    from symloc.figures.mcl import amcl_symmetric_figure

    summary, trials, grid = run_room("rectangle", 1, 4, duration=3.0, progress=False)
    assert "confident_wrong_without_rival_check" in summary
    assert summary["confident_wrong"] <= summary["confident_wrong_without_rival_check"]
    out = amcl_symmetric_figure([summary], {"rectangle": (grid, trials[0])}, tmp_path / "s.png")
    assert out.read_bytes()[:4] == b"\x89PNG"
