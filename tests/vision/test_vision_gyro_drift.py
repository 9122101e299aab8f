"""A round room's keyframe headings from gyro-odometry with its drift fitted to image pairs:
the fit recovers bias and scale, drops false pairs, its std covers the error, positions turn
about the centre, and too little evidence leaves SLAM's poses."""

from __future__ import annotations

import math

import numpy as np
import pytest

import symloc.vision.gyro_drift as gyro_drift
from symloc.errors import ConfigurationError
from symloc.geometry import wrap_angle
from symloc.vision.bow import BowVector
from symloc.vision.gyro_drift import DriftSettings, fit_drift, round_room_keyframes
from symloc.vision.keyframes import Keyframe
from symloc.vision.orb import OrbFeatures
from symloc.vision.rotation_averaging import PairMeasurements

BIAS = math.radians(-0.1)  # rad/s: a gyro whose start-up calibration left 0.1 deg/s
SCALE = 0.003


def _trip(rng: np.random.Generator, n: int = 120, seconds: float = 200.0):
    """True headings of a trip that turns both ways, its times, the gyro's and SLAM's."""
    t = np.linspace(0.0, seconds, n)
    turned = np.cumsum(rng.normal(0.0, 0.25, n))  # rad, unwrapped
    turned -= turned[0]
    true = turned + 0.4
    odom = true + BIAS * t + SCALE * turned
    slam = true + rng.normal(0.0, math.radians(0.9), n)
    return t, true, odom, slam


def _pairs(rng: np.random.Generator, true: np.ndarray, count: int, noise_deg: float = 0.4):
    n = true.size
    i = rng.integers(0, n - 1, count)
    j = np.minimum(n - 1, i + rng.integers(1, n, count))
    keep = i < j
    i, j = i[keep], j[keep]
    yaws = np.asarray(
        wrap_angle(true[j] - true[i] + rng.normal(0, math.radians(noise_deg), i.size))
    )
    return PairMeasurements(
        pairs=np.column_stack([i, j]).astype(np.int64),
        yaws=yaws,
        sigmas=np.full(i.size, math.radians(0.6)),
        inliers=np.full(i.size, 100, np.int64),
    )


def test_fit_recovers_bias_and_scale_and_its_std_covers_the_error() -> None:
    rng = np.random.default_rng(3)
    t, true, odom, slam = _trip(rng)
    fit = fit_drift(odom, t, slam, _pairs(rng, true, 200))
    assert fit is not None
    assert fit.bias == pytest.approx(BIAS, abs=math.radians(0.005))
    assert fit.scale == pytest.approx(SCALE, abs=0.001)
    err = np.abs(np.asarray(wrap_angle(fit.headings - true)))
    # the gyro alone is off by up to 20 deg, SLAM by up to 3; the fit's worst stays inside
    # three of its own stds and under half a degree
    assert math.degrees(np.abs(np.asarray(wrap_angle(odom - true))).max()) > 15.0
    assert err.max() < 3.0 * fit.heading_std
    assert math.degrees(err.max()) < 0.5
    assert "bias" in fit.summary()


def test_false_pairs_are_dropped() -> None:
    rng = np.random.default_rng(4)
    t, true, odom, slam = _trip(rng)
    good = _pairs(rng, true, 150)
    bad_yaws = good.yaws.copy()
    bad_yaws[:12] += math.radians(5.0)  # a look-alike wall matched the wrong way
    fit = fit_drift(
        odom, t, slam, PairMeasurements(good.pairs, bad_yaws, good.sigmas, good.inliers)
    )
    assert fit is not None
    assert not fit.used[:12].any()
    assert fit.used[12:].mean() > 0.95
    assert fit.bias == pytest.approx(BIAS, abs=math.radians(0.005))


def test_too_few_pairs_give_no_fit() -> None:
    rng = np.random.default_rng(5)
    t, true, odom, slam = _trip(rng)
    assert fit_drift(odom, t, slam, _pairs(rng, true, 6), DriftSettings(min_pairs=10)) is None
    assert fit_drift(odom, t, slam, PairMeasurements.empty()) is None


def test_bad_input_names_the_field() -> None:
    with pytest.raises(ConfigurationError, match=r"DriftSettings\.max_pairs"):
        DriftSettings(min_pairs=20, max_pairs=10)
    with pytest.raises(ConfigurationError, match=r"DriftSettings\.rate_noise_density"):
        DriftSettings(rate_noise_density=-1.0)
    rng = np.random.default_rng(6)
    t, true, odom, slam = _trip(rng)
    with pytest.raises(ConfigurationError, match="stamps"):
        fit_drift(odom, t[:-1], slam, _pairs(rng, true, 50))


def _keyframe(pose: np.ndarray, stamp: float) -> Keyframe:
    return Keyframe(
        pose=pose, features=OrbFeatures.empty(), bow=BowVector.from_dict({}), stamp=stamp
    )


def test_round_room_keyframes_turn_about_the_centre(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(7)
    t, true, odom, slam = _trip(rng, n=60, seconds=120.0)
    centre = np.array([1.0, -2.0])
    radius = 2.0
    # SLAM's pose error in a round room is a turn about its centre: position and heading
    err = slam - true
    ang = true * 0.0 + np.linspace(0.0, 2 * math.pi, t.size, endpoint=False)
    true_xy = centre + radius * np.column_stack([np.cos(ang), np.sin(ang)])
    slam_xy = centre + radius * np.column_stack([np.cos(ang + err), np.sin(ang + err)])
    kfs = [
        _keyframe(np.array([x, y, h]), s)
        for (x, y), h, s in zip(slam_xy, np.asarray(wrap_angle(slam)), t, strict=True)
    ]
    meas = _pairs(rng, true, 150)
    monkeypatch.setattr(gyro_drift, "measure_pairs", lambda *a, **k: meas)
    out, fit = round_room_keyframes(kfs, odom, centre, np.eye(3))
    assert fit is not None
    new = np.array([kf.pose for kf in out])
    heading_err = np.abs(np.asarray(wrap_angle(new[:, 2] - true)))
    moved = np.hypot(*(new[:, :2] - true_xy).T)
    before = np.hypot(*(slam_xy - true_xy).T)
    assert math.degrees(heading_err.max()) < 0.6
    assert moved.max() < radius * math.radians(0.6)
    assert before.max() > 2.5 * moved.max()
    assert np.allclose(np.hypot(*(new[:, :2] - centre).T), radius)
    # how far SLAM's trip was off along the wall, its common turn left out, as the fit sees it
    along = radius * np.asarray(wrap_angle(err - np.mean(err)), np.float64)
    truth_rms = math.sqrt(float(np.mean(np.square(along))))
    assert fit.position_std == pytest.approx(truth_rms, rel=0.25, abs=0.004)
    assert "off along the wall" in fit.summary()


def test_round_room_keyframes_without_evidence_stay(monkeypatch: pytest.MonkeyPatch) -> None:
    kfs = [_keyframe(np.array([float(i), 0.0, 0.1 * i]), float(i)) for i in range(5)]
    monkeypatch.setattr(gyro_drift, "measure_pairs", lambda *a, **k: PairMeasurements.empty())
    out, fit = round_room_keyframes(kfs, [0.1 * i for i in range(5)], [0.0, 0.0], np.eye(3))
    assert fit is None
    assert all(np.array_equal(a.pose, b.pose) for a, b in zip(out, kfs, strict=True))


def test_anchor_flags_must_match_the_keyframes() -> None:
    kfs = [_keyframe(np.array([float(i), 0.0, 0.1 * i]), float(i)) for i in range(5)]
    with pytest.raises(ConfigurationError, match="anchor"):
        round_room_keyframes(kfs, [0.1 * i for i in range(5)], [0.0, 0.0], np.eye(3), anchor=[1, 0])


@pytest.mark.parametrize("which", ["rotation", "position"])
def test_a_visual_maps_declared_error_is_read_back_and_checked(tmp_path, which: str) -> None:
    from symloc.vision.gyro_drift import (
        META_KEY,
        POSITION_META_KEY,
        declared_position_std,
        declared_rotation_std,
    )
    from symloc.vision.visual_map import VisualMap

    key, read = (
        (META_KEY, declared_rotation_std)
        if which == "rotation"
        else (POSITION_META_KEY, declared_position_std)
    )
    with VisualMap(tmp_path / "map.sqlite") as vm:
        assert read(vm) is None
        vm.set_meta(key, repr(0.007))
        assert read(vm) == pytest.approx(0.007)
        for bad in ("nan", "-0.01", "0", "half a degree"):
            vm.set_meta(key, bad)
            with pytest.raises(ConfigurationError, match=f"map.sqlite: meta '{key}'"):
                read(vm)


def test_the_data_sheet_prior_keeps_a_short_trips_few_pairs_from_freeing_the_scale() -> None:
    # a small room's one lap after a half turn in place: a minute, few pairs, all along the
    # lap, which turns steadily (the angle turned grows with the time: the pairs see bias and
    # scale only together); the turn in place needs the scale alone, and the prior (the
    # gyro's data sheet) holds it
    rng = np.random.default_rng(7)
    n, seconds = 35, 60.0
    t = np.linspace(0.0, seconds, n)
    lap = (t - 5.0) / 55.0
    lap = lap + 0.03 * np.sin(2.0 * math.pi * lap)  # the speed varies a little
    turned = np.where(t < 5.0, math.pi * t / 5.0, math.pi + 2.0 * math.pi * lap)
    bias, scale = math.radians(0.05), 0.002
    true = turned + 0.3
    odom = true + bias * t + scale * turned
    slam = true + rng.normal(0.0, math.radians(0.9), n)
    i = rng.integers(4, n - 4, 16)
    j = i + rng.integers(1, 4, 16)
    meas = PairMeasurements(
        pairs=np.column_stack([i, j]).astype(np.int64),
        yaws=np.asarray(wrap_angle(true[j] - true[i] + rng.normal(0, math.radians(0.4), 16))),
        sigmas=np.full(16, math.radians(0.6)),
        inliers=np.full(16, 100, np.int64),
    )
    free = fit_drift(odom, t, slam, meas, DriftSettings(bias_std=0.0, scale_std=0.0))
    held = fit_drift(odom, t, slam, meas)
    assert free is not None
    assert held is not None
    # the pairs alone know the bias-and-scale mix, not each: a wide heading std
    assert held.heading_std < 0.5 * free.heading_std
    assert abs(held.scale) < 3.0 * DriftSettings().scale_std
    err = np.abs(np.asarray(wrap_angle(held.headings - true)))
    assert err.max() < 3.0 * held.heading_std
    with pytest.raises(ConfigurationError, match=r"DriftSettings\.bias_std"):
        DriftSettings(bias_std=-1.0)
