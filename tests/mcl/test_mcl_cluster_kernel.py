"""The compiled clustering equals the NumPy/SciPy definition bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.mcl.clustering import cluster_particles, cluster_particles_reference


def _same(a, b) -> None:
    for name in ("labels", "weights", "means", "covariances", "counts"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 3000),
    spread=st.sampled_from([0.05, 0.4, 3.0, 40.0]),
    blobs=st.integers(1, 5),
    equal=st.booleans(),
)
def test_compiled_clustering_bit_identical(seed, n, spread, blobs, equal):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-20, 20, (blobs, 2))
    k = rng.integers(0, blobs, n)
    xy = centres[k] + rng.normal(0, spread, (n, 2))
    th = rng.choice([np.pi, -np.pi + 1e-9, 0.0, 3.1]) + rng.normal(0, 0.3, n)
    th = np.pi - np.mod(np.pi - th, 2 * np.pi)
    parts = np.column_stack([xy, th])
    if rng.random() < 0.3:
        parts = np.repeat(parts[: max(1, n // 7)], 7, axis=0)[:n]  # resampled: duplicates
    w = np.full(parts.shape[0], 1.0) if equal else rng.random(parts.shape[0])
    if rng.random() < 0.2:
        w[k[: parts.shape[0]] == 0] = 0.0  # a cluster of zero weight
        if w.sum() == 0:
            w[0] = 1.0
    _same(cluster_particles(parts, w), cluster_particles_reference(parts, w))


def test_heading_wrap_joins_bins_across_pi():
    parts = np.array([[0.1, 0.1, np.pi - 0.01], [0.1, 0.1, -np.pi + 0.01]])
    stats = cluster_particles(parts, np.ones(2))
    assert len(stats) == 1
    _same(stats, cluster_particles_reference(parts, np.ones(2)))


def test_non_finite_particles_refused():
    with pytest.raises(ConfigurationError, match="particles"):
        cluster_particles(np.array([[np.nan, 0.0, 0.0]]), np.ones(1))
