"""The shipped vocabulary, the Table 3 protocol and the keyframes experiment, at small sizes."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import vision_helpers as helpers

from symloc.bench.keyframes import run_keyframes
from symloc.bench.table3 import run_table3, wall_headings
from symloc.cli.main import main
from symloc.vision.default_vocabulary import DEFAULT_VOCABULARY_PATH, default_vocabulary


def test_shipped_vocabulary() -> None:
    extractor = helpers.extractor()
    wall_photos = helpers.wall_photos()
    assert DEFAULT_VOCABULARY_PATH.stat().st_size < 5 * 2**20
    voc = default_vocabulary()
    assert (voc.k, voc.L) == (10, 5)
    assert voc.n_words > 50000
    bow = voc.bow(extractor.extract(wall_photos[0]).descriptors)
    assert len(bow) > 100
    assert bow.values.sum() == pytest.approx(1.0)


def test_wall_headings_are_clockwise_from_the_one_nearest_zero() -> None:
    corners = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    h = wall_headings(corners, np.zeros(2))
    assert np.degrees(h) == pytest.approx([0.0, -90.0, 180.0, 90.0])


def test_table3_small_run_never_picks_a_wrong_direction() -> None:
    res = run_table3(trials=3, rng=1, progress=False)
    d = res.to_dict()
    s = np.asarray(d["similarity"])
    assert s.shape == (4, 4)
    assert np.all(np.diag(s) > 2 * (s.sum(axis=1) - np.diag(s)) / 3)  # diagonal dominates
    assert d["trials"] == 12
    assert d["counts"]["wrong"] == 0
    assert d["untextured"]["trials"] == 12
    assert d["untextured"]["wrong"] == 0
    assert d["untextured"]["correct"] == 0
    # with a FAST threshold low enough for >= 100 keypoints, the *decision* must say undetermined
    sens = d["untextured_sensitive_orb"]
    assert sens["trials"] == 12
    assert sens["wrong_after_retries"] == 0
    assert sens["correct_after_retries"] == 0
    assert d["heading_error_deg_median"] < 1.0  # offset correction works (robot off by <= 5 deg)


def test_keyframes_policy_stores_more(tmp_path) -> None:  # type: ignore[no-untyped-def]
    a, b = run_keyframes(m=4, step_deg=45.0, rng=0)
    assert (a.count, b.count) == (4, 8)
    assert b.bytes_features > a.bytes_features
    assert a.bytes_with_images > a.bytes_features


def test_keyframes_cli_writes_json_and_figure(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "kf.json"
    code = main(
        ["experiment", "keyframes", "--step-deg", "90", "--json", str(out), "--out", str(tmp_path)]
    )
    assert code == 0
    data = json.loads(out.read_text())
    assert [p["count"] for p in data["policies"]] == [4, 4]
    assert (tmp_path / "keyframes.png").stat().st_size > 1000
    assert "seed: 0" in capsys.readouterr().out
    assert math.isfinite(data["policies"][0]["bytes_features"])
