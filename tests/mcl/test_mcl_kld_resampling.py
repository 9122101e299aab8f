from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.mcl.kld_sampling import kld_sample_count, kld_stop_index, pf_z_quantile
from symloc.mcl.resampling import low_variance_counts, low_variance_resample


def _fox(k, eps, z):
    """Fox (2003), eq. 7, written out term by term."""
    a = 2.0 / (9.0 * (k - 1))
    return math.ceil((k - 1) / (2 * eps) * (1 - a + math.sqrt(a) * z) ** 3)


def test_pf_z_is_a_quantile():
    assert pf_z_quantile(0.99) == pytest.approx(2.326348, abs=1e-6)
    assert pf_z_quantile(0.5 + 1e-12) == pytest.approx(0.0, abs=1e-6)
    with pytest.raises(ConfigurationError, match="pf_z"):
        pf_z_quantile(1.0)


def test_pf_z_quantile_is_scipys_ndtri():
    from scipy.special import ndtri

    assert pf_z_quantile(0.99) == float(ndtri(0.99))  # nav2's default: the same double
    for p in np.linspace(0.5, 1.0, 1001)[1:-1]:
        assert pf_z_quantile(float(p)) == pytest.approx(float(ndtri(p)), rel=2e-15)


def test_the_filter_does_not_import_scipy_special():
    code = (
        "import sys, symloc.mcl.amcl, symloc.mcl.confidence; print('scipy.special' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("k", [2, 3, 10, 50, 200, 1000])
def test_kld_counts_match_fox(k):
    z = pf_z_quantile(0.99)
    assert kld_sample_count(k, 0.05, z, 1, 10**9) == _fox(k, 0.05, z)
    assert kld_sample_count(k, 0.01, z, 1, 10**9) == _fox(k, 0.01, z)


def test_kld_counts_clamped_and_k_le_1():
    z = pf_z_quantile(0.99)
    assert kld_sample_count(1, 0.05, z, 500, 2000) == 2000
    assert kld_sample_count(2, 0.05, z, 500, 2000) == 500
    assert kld_sample_count(10**6, 0.05, z, 500, 2000) == 2000
    np.testing.assert_array_equal(
        kld_sample_count(np.array([2, 50]), 0.05, z, 1, 10**9),
        [_fox(2, 0.05, z), _fox(50, 0.05, z)],
    )
    with pytest.raises(ConfigurationError, match="pf_err"):
        kld_sample_count(5, 0.0, z, 1, 10)


def test_nav2_pf_z_gives_fewer_particles():
    # nav2 passes 0.99 as z; the quantile gives the larger (correct) bound
    assert kld_sample_count(100, 0.05, 0.99, 1, 10**9) < kld_sample_count(
        100, 0.05, pf_z_quantile(0.99), 1, 10**9
    )


@settings(max_examples=30, deadline=None)
@given(st.lists(st.integers(0, 40), min_size=1, max_size=400), st.integers(1, 50))
def test_kld_stop_index_matches_sequential_loop(keys, min_p):
    keys_a = np.array(keys, dtype=np.int64)
    z = pf_z_quantile(0.99)
    max_p = 400
    # amcl's loop: add samples one at a time, stop once count > bound(k)
    seen: set[int] = set()
    expected = len(keys)
    for i, kk in enumerate(keys):
        seen.add(kk)
        if i + 1 > kld_sample_count(len(seen), 0.05, z, min_p, max_p):
            expected = i + 1
            break
    assert kld_stop_index(keys_a, 0.05, z, min_p, max_p) == expected


def test_low_variance_counts_properties():
    w = np.array([0.125, 0.0, 0.5, 0.0625, 0.3125])  # exact in binary
    for m in (16, 21):
        for u0 in (0.0, 0.3, 0.999):
            c = low_variance_counts(w, m, u0)
            assert c.sum() == m
            # systematic resampling gives floor or ceil of M w_i copies
            assert np.all(c >= np.floor(m * w))
            assert np.all(c <= np.ceil(m * w))
        assert c[1] == 0


def test_low_variance_unbiased():
    rng = np.random.default_rng(3)
    w = rng.random(37) ** 3
    m = 100
    # average over the offset u0 (uniform in [0, 1)) on a fine grid: E[count_i] = M w_i / sum w
    u = (np.arange(4000) + 0.5) / 4000
    mean = np.mean([low_variance_counts(w, m, x) for x in u], axis=0)
    np.testing.assert_allclose(mean, m * w / w.sum(), atol=2e-3)
    # and by sampling
    idx = np.concatenate([low_variance_resample(w, m, rng) for _ in range(300)])
    freq = np.bincount(idx, minlength=w.size) / (300 * m)
    np.testing.assert_allclose(freq, w / w.sum(), atol=0.01)


def test_resample_indices_sorted_and_sized():
    idx = low_variance_resample(np.ones(10), 25, np.random.default_rng(0))
    assert idx.size == 25
    assert np.all(np.diff(idx) >= 0)


@pytest.mark.parametrize(
    "w", [np.zeros(4), np.array([1.0, np.nan]), np.array([1.0, -0.5]), np.array([])]
)
def test_resampling_rejects_bad_weights(w):
    with pytest.raises(ConfigurationError, match="weights"):
        low_variance_counts(w, 10, 0.5)


@pytest.mark.parametrize("seed", range(6))
def test_kld_stop_kernel_equals_numpy(seed):
    """The compiled one-pass stop (what the filter runs) against its NumPy definition."""
    from symloc.mcl import kernels
    from symloc.mcl.clustering import BIN_ANGLE, BIN_XY, N_ANGLE_BINS, bin_keys

    rng = np.random.default_rng(seed)
    z = pf_z_quantile(0.99)
    for spread, n, (lo, hi), err in [
        (0.05, 2000, (500, 2000), 0.01),
        (0.6, 2000, (500, 2000), 0.01),
        (30.0, 5000, (100, 5000), 0.05),
        (2.0, 300, (10, 300), 0.2),
        (1e-3, 50, (50, 60), 0.01),
        (5.0, 1, (1, 10), 0.01),
    ]:
        p = np.column_stack(
            [
                rng.normal(rng.uniform(-100, 100), spread, n),
                rng.normal(rng.uniform(-100, 100), spread, n),
                rng.uniform(-np.pi, np.pi, n),
            ]
        )
        p[: n // 7, 2] = np.pi  # the heading bins' edge
        got = kernels.kld_stop(p, BIN_XY, BIN_ANGLE, N_ANGLE_BINS, err, z, lo, hi)
        assert got == kld_stop_index(bin_keys(p), err, z, lo, hi)
    p[0, 1] = np.nan
    assert kernels.kld_stop(p, BIN_XY, BIN_ANGLE, N_ANGLE_BINS, 0.01, z, 1, 10) == -1
