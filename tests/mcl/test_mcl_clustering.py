from __future__ import annotations

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.mcl.clustering import bin_keys, cluster_particles


def _blob(rng, mean, n, sxy=0.05, sth=0.03):
    p = rng.normal(0, 1, (n, 3)) * [sxy, sxy, sth] + mean
    p[:, 2] = np.pi - np.mod(np.pi - p[:, 2], 2 * np.pi)
    return p


def test_two_blobs_two_clusters_with_own_covariance():
    rng = np.random.default_rng(0)
    a = _blob(rng, [1.0, 1.0, 0.5], 600)
    b = _blob(rng, [5.0, 3.0, -2.0], 400, sxy=0.1)
    st = cluster_particles(np.vstack([a, b]), np.ones(1000))
    assert len(st) == 2
    np.testing.assert_allclose(st.weights, [0.6, 0.4])
    np.testing.assert_allclose(st.means[0], [1.0, 1.0, 0.5], atol=0.02)
    np.testing.assert_allclose(st.means[1], [5.0, 3.0, -2.0], atol=0.03)
    # each cluster's own covariance, not the whole set's (which would be metres^2)
    assert st.covariances[0][0, 0] == pytest.approx(0.05**2, rel=0.2)
    assert st.covariances[1][1, 1] == pytest.approx(0.1**2, rel=0.2)
    assert st.covariances[0][2, 2] == pytest.approx(0.03**2, rel=0.25)
    assert np.all(st.labels[:600] == 0)
    assert np.all(st.labels[600:] == 1)
    h = st.hypotheses()
    assert h[0].n_particles == 600
    assert h[0].weight == pytest.approx(0.6)


def test_cluster_across_the_pi_seam():
    rng = np.random.default_rng(1)
    p = _blob(rng, [2.0, 2.0, np.pi], 1000, sth=0.05)
    assert np.any(p[:, 2] < -3.0)
    assert np.any(p[:, 2] > 3.0)
    st = cluster_particles(p, np.ones(len(p)))
    assert len(st) == 1  # nav2 would split it in two
    assert abs(abs(st.means[0, 2]) - np.pi) < 0.01
    assert st.covariances[0][2, 2] == pytest.approx(0.05**2, rel=0.2)


def test_weighted_mean_and_weights_normalised():
    p = np.array([[0.1, 0.1, 0.0], [0.2, 0.1, 0.0], [8.0, 8.0, 0.0]])
    st = cluster_particles(p, np.array([1.0, 3.0, 4.0]))
    np.testing.assert_allclose(st.weights, [0.5, 0.5])
    # ties keep the first cluster first; the pair has weighted mean x = 0.175
    means = {round(m[0], 3) for m in st.means}
    assert 0.175 in means
    assert 8.0 in means


def test_neighbouring_bins_join_distant_do_not():
    p = np.array([[0.1, 0.1, 0.0], [0.6, 0.6, 0.18], [1.6, 0.1, 0.0]])
    st = cluster_particles(p, np.ones(3))
    assert len(st) == 2  # the first two touch diagonally, the third is two bins away


def test_bin_keys_distinguish_bins():
    k = bin_keys(np.array([[0.1, 0.1, 0.0], [0.4, 0.4, 0.1], [0.6, 0.1, 0.0], [0.1, 0.1, 0.2]]))
    assert k[0] == k[1]
    assert len(set(k.tolist())) == 3


@pytest.mark.parametrize(
    ("p", "w", "match"),
    [
        (np.zeros((0, 3)), np.zeros(0), "shapes"),
        (np.zeros((2, 2)), np.ones(2), "shapes"),
        (np.zeros((2, 3)), np.zeros(2), "weights"),
        (np.zeros((2, 3)), np.array([1.0, np.nan]), "weights"),
    ],
)
def test_errors(p, w, match):
    with pytest.raises(ConfigurationError, match=match):
        cluster_particles(p, w)
