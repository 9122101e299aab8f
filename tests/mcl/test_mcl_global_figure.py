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
