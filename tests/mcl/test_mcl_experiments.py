from __future__ import annotations

import functools
import math
from types import SimpleNamespace

import numpy as np
import pytest

from symloc.experiments.amcl_carmen import find_carmen_dir, noisy_odometry, tracking
from symloc.experiments.amcl_symmetric import classify, run_room, symmetric_images
from symloc.geometry import wrap_angle


def test_symmetric_images_of_a_square():
    imgs = symmetric_images(np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0]), 4)
    np.testing.assert_allclose(imgs[1], [0.0, 1.0, np.pi / 2], atol=1e-12)
    np.testing.assert_allclose(imgs[2], [-1.0, 0.0, np.pi], atol=1e-12)
    assert symmetric_images(np.array([1.0, 2.0, 0.5]), np.zeros(2), 1).shape == (1, 3)


def test_classify():
    imgs = symmetric_images(np.array([1.0, 0.0, 0.0]), np.zeros(2), 4)
    tol = math.radians(10)
    assert classify(np.array([1.05, 0.0, 0.05]), imgs, 0.3, tol) == ("correct", 0)
    assert classify(np.array([0.0, -1.0, -np.pi / 2]), imgs, 0.3, tol) == ("symmetric_copy", 3)
    # right place, wrong heading: not a symmetry image
    assert classify(np.array([1.0, 0.0, 1.0]), imgs, 0.3, tol) == ("not_converged", -1)


def test_run_room_small():
    summary, trials, grid = run_room(
        "rectangle",
        2,
        3,
        duration=6.0,
        progress=False,
        params=None,
    )
    assert summary["trials"] == 2
    assert summary["order"] == 2
    assert summary["correct"] + summary["symmetric_copy"] + summary["not_converged"] == 2
    assert all(np.all(np.isfinite(t.estimate)) for t in trials)
    assert grid.resolution == 0.05


def test_noisy_odometry_zero_noise_is_the_truth():
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.normal(0, 0.3, (50, 3)), axis=0)
    t[:, 2] = wrap_angle(t[:, 2])
    o = noisy_odometry(t, (0.0, 0.0, 0.0, 0.0), rng)
    np.testing.assert_allclose(o[:, :2], t[:, :2], atol=1e-9)
    noisy = noisy_odometry(t, (0.01, 0.01, 0.01, 0.01), rng)
    assert np.abs(noisy[1:, :2] - t[1:, :2]).max() > 0.01


def test_a_cached_map_is_used_only_for_the_log_it_was_built_from(tmp_path):
    from symloc.experiments.amcl_carmen import build_map
    from symloc.scan import LaserScan

    def log(shift):  # type: ignore[no-untyped-def]
        ranges = np.full(90, 2.0)
        scan = LaserScan(angle_min=-np.pi / 2, angle_increment=np.pi / 90, range_min=0.0,
                         range_max=10.0, ranges=ranges, stamp=0.0)  # fmt: skip
        pose = np.array([shift, 0.0, 0.0])
        return SimpleNamespace(scans=[SimpleNamespace(laser_pose=pose, scan=scan, stamp=0.0)])

    cache = tmp_path / "amcl_carmen_map_x.npz"
    first = build_map(log(0.0), cache=cache)
    assert cache.is_file()
    assert np.array_equal(build_map(log(0.0), cache=cache).data, first.data)  # from the cache
    other = build_map(log(1.0), cache=cache)  # another log under the same name: built anew
    assert not np.array_equal(np.asarray(other.origin), np.asarray(first.origin)) or not (
        np.array_equal(other.data, first.data)
    )
    np.savez_compressed(cache, data=first.data, resolution=0.05, origin=np.asarray(first.origin))
    again = build_map(log(1.0), cache=cache)  # a cache of an older version (no key): rebuilt
    assert np.array_equal(again.data, other.data)
    cache.write_bytes(b"not a zip file")  # a truncated or foreign file: rebuilt, not a crash
    assert np.array_equal(build_map(log(1.0), cache=cache).data, other.data)
    assert np.array_equal(build_map(log(1.0), cache=cache).data, other.data)  # and cached


@pytest.mark.shared_data
def test_tracking_on_the_start_of_the_aces_log():
    folder = find_carmen_dir()
    if folder is None or not (folder / "aces-corrected.log.gz").is_file():
        pytest.skip("CARMEN logs not found (../shared/data/carmen or SYMLOC_SHARED_DATA)")
    from symloc.experiments.amcl_carmen import _LogData, build_map
    from symloc.io.carmen import read_carmen
    from symloc.mcl import AmclParams

    log = read_carmen(folder / "aces-corrected.log.gz")
    short = SimpleNamespace(scans=log.scans[:40])
    grid = build_map(short)
    truth = log.laser_poses[:40].copy()
    truth[:, 2] = wrap_angle(truth[:, 2])
    p = AmclParams(
        laser_model_type="likelihood_field_prob",
        alpha1=0.01,
        alpha2=0.01,
        alpha3=0.01,
        alpha4=0.01,
        max_particles=1000,
        laser_max_range=49.9,
    )
    res = tracking(_LogData("aces", short, grid, truth), p, (0.01,) * 4, 0)
    assert res["mean_error_m"] < 0.2
    assert res["odometry_only_mean_error_m"] > res["mean_error_m"]


@pytest.mark.shared_data
def test_global_localization_reports_the_confidence_columns(monkeypatch):
    folder = find_carmen_dir()
    if folder is None or not (folder / "intel-corrected.log.gz").is_file():
        pytest.skip("CARMEN logs not found (../shared/data/carmen or SYMLOC_SHARED_DATA)")
    from symloc.experiments.amcl_carmen import _LogData, build_map, global_localization
    from symloc.io.carmen import read_carmen
    from symloc.mcl import AmclParams

    log = read_carmen(folder / "intel-corrected.log.gz")
    short = SimpleNamespace(scans=log.scans[:60], stamps=log.stamps[:60])
    grid = build_map(short)
    truth = log.laser_poses[:60].copy()
    truth[:, 2] = wrap_angle(truth[:, 2])
    p = AmclParams(
        laser_model_type="likelihood_field_prob",
        max_particles=3000,
        min_particles=300,
        laser_max_range=49.9,
        alpha1=0.01,
        alpha2=0.01,
        alpha3=0.01,
        alpha4=0.01,
    )
    trace: list = []
    localize = functools.partial(
        global_localization,
        _LogData("intel", short, grid, truth),
        p,
        (0.01,) * 4,
        1,
        starts=2,
        window=20,
        progress=False,
    )
    gl = localize(trace=trace)
    assert gl["starts"] == 2
    assert len(trace) == 2
    assert 0 <= gl["runs_confident_at_end"] <= 2
    for run, tr in zip(gl["runs"], trace, strict=True):
        c = tr["confident"]
        assert run["confident_scans"] == int(c.sum())
        if c.any():
            assert run["max_error_while_confident_m"] == pytest.approx(float(tr["dxy"][c].max()))
        assert len(tr["reason"]) == len(c)
    # AMCL's runs draw from streams of their own: symloc drawing more random numbers (here:
    # a thousand more per start) leaves AMCL's figures as they were
    import symloc.experiments.amcl_carmen as ac

    real = ac.symloc_claims

    def greedy(data, params, odom, s, stop, rng, **kw):  # type: ignore[no-untyped-def]
        rng.random(1000)
        return real(data, params, odom, s, stop, rng, **kw)

    monkeypatch.setattr(ac, "symloc_claims", greedy)
    again = localize()
    for a, b in zip(gl["runs"], again["runs"], strict=True):
        assert a["final_error_m"] == b["final_error_m"]
        assert a["confident_scans"] == b["confident_scans"]


@pytest.mark.shared_data
def test_amcl_tracking_error_without_overrides_is_the_experiments_tracking_error(tmp_path):
    """amcl_tracking_error replays the experiment's own odometry draw and AMCL: without
    overrides its mean error is the experiment's (tracking, the same seed); an override
    changes the run."""
    folder = find_carmen_dir()
    if folder is None or not (folder / "aces-corrected.log.gz").is_file():
        pytest.skip("CARMEN logs not found (../shared/data/carmen or SYMLOC_SHARED_DATA)")
    from symloc.experiments.amcl_carmen import (
        _LogData,
        amcl_tracking_error,
        log_data,
        tracking_params,
        tracking_stream,
    )

    full = log_data("aces", folder / "aces-corrected.log.gz", cache=tmp_path / "aces.npz")
    assert (tmp_path / "aces.npz").is_file()
    n = 30
    data = _LogData("aces", SimpleNamespace(scans=full.log.scans[:n]), full.grid, full.truth[:n])
    same = tracking(data, tracking_params(0.01), (0.01,) * 4, tracking_stream("aces", 3))
    got = amcl_tracking_error(data, 3)
    assert got["mean_error_m"] == same["mean_error_m"]
    assert got["max_error_m"] == same["max_error_m"]
    every_scan = amcl_tracking_error(data, 3, update_min_d=0.0, update_min_a=0.0)
    assert every_scan["mean_error_m"] != got["mean_error_m"]
