"""The node's camera_dist_coeffs parameter reaches the orientation decision."""

from __future__ import annotations

import pytest

from symloc.errors import ConfigurationError
from symloc.ros.params import NodeParams


def test_camera_dist_coeffs_parsed_and_validated() -> None:
    p = NodeParams.from_yaml(
        "symloc:\n  ros__parameters:\n    camera_dist_coeffs: [0.135, -0.234, 0.0007, 0.0048]\n"
    )
    assert p.camera_dist_coeffs == (0.135, -0.234, 0.0007, 0.0048, 0.0)
    assert NodeParams().camera_dist_coeffs == ()
    for bad in ("[1, 2, 3]", "[.nan, 0, 0, 0]", "'abc'"):
        with pytest.raises(ConfigurationError, match="camera_dist_coeffs"):
            NodeParams.from_yaml(f"symloc:\n  ros__parameters:\n    camera_dist_coeffs: {bad}\n")


def test_open_places_passes_the_coefficients(tmp_path) -> None:
    from symloc.ros.assemble import open_places

    params = NodeParams(
        visual_map=str(tmp_path / "places.db"),
        mode="build_visual_map",
        camera_dist_coeffs=(0.1, -0.2, 0.0, 0.0, 0.0),
    )
    store = open_places(params)
    assert store.dist_coeffs == (0.1, -0.2, 0.0, 0.0, 0.0)
    plain = open_places(NodeParams(visual_map=str(tmp_path / "b.db"), mode="build_visual_map"))
    assert plain.dist_coeffs == (0.0,) * 5
