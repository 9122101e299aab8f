"""The one pose hypothesis: a candidate pose, or a particle cluster with its spread."""

from __future__ import annotations

import numpy as np
import pytest

import symloc.localizer
import symloc.localizer.types
import symloc.mcl
from symloc.errors import ConfigurationError
from symloc.hypothesis import Hypothesis
from symloc.mcl.clustering import cluster_particles


def test_a_candidate_pose_has_no_spread() -> None:
    h = Hypothesis(pose=np.array([1.0, 2.0, 0.5]), weight=0.25)
    assert h.covariance is None
    assert h.n_particles == 0
    assert h.pose.dtype == np.float64
    assert isinstance(h.weight, float)


def test_one_class_under_every_name() -> None:
    assert symloc.localizer.Hypothesis is Hypothesis
    assert symloc.localizer.types.Hypothesis is Hypothesis
    assert symloc.mcl.Hypothesis is Hypothesis


def test_clusters_carry_pose_covariance_and_count() -> None:
    rng = np.random.default_rng(0)
    p = np.column_stack([rng.normal(2.0, 0.05, 300), rng.normal(3.0, 0.05, 300), np.zeros(300)])
    stats = cluster_particles(p, np.ones(len(p)))
    (h,) = stats.hypotheses()
    assert h.covariance is not None
    np.testing.assert_array_equal(h.pose, stats.means[0])
    np.testing.assert_array_equal(h.covariance, stats.covariances[0])
    assert h.n_particles == 300
    assert h.weight == pytest.approx(1.0)


def test_a_float64_pose_is_kept_as_it_is() -> None:
    pose = np.array([1.0, 2.0, 0.5])
    assert Hypothesis(pose, 1.0).pose is pose


def test_equality_is_identity() -> None:
    a = Hypothesis(np.zeros(3), 1.0)
    b = Hypothesis(np.zeros(3), 1.0)
    assert a == a
    assert a != b
    assert len({a, b}) == 2


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"pose": np.zeros(2), "weight": 1.0}, r"Hypothesis\.pose: expected shape \(3,\)"),
        (
            {"pose": np.zeros(3), "weight": 1.0, "covariance": np.eye(2)},
            r"Hypothesis\.covariance: expected shape \(3, 3\)",
        ),
        (
            {"pose": np.zeros(3), "weight": 1.0, "n_particles": -1},
            r"Hypothesis\.n_particles: expected >= 0",
        ),
    ],
)
def test_bad_fields_are_named(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        Hypothesis(**kwargs)  # type: ignore[arg-type]
