"""Scans paired with the odometry at their stamp (symloc.ros.pairing), without a node."""

from __future__ import annotations

import numpy as np
import pytest

from symloc.odometry import OdometryReading
from symloc.ros.pairing import NO_ODOM_AT_STAMP, OdometryBuffer, Paired, ScanPairing, Unpaired
from symloc.scan import LaserScan


def _scan(stamp: float) -> LaserScan:
    return LaserScan(-np.pi, np.pi / 2, 0.1, 10.0, np.ones(4), stamp=stamp)


def _odom(*stamps: float) -> OdometryBuffer:
    buf = OdometryBuffer()
    for t in stamps:
        assert buf.add(OdometryReading(np.array([t, 0.0, 0.1 * t]), t), max_age=10.0)
    return buf


def test_odometry_is_interpolated_at_the_scan_stamp() -> None:
    buf = _odom(1.0, 2.0)
    got = buf.at(1.25, tolerance=0.5)
    assert isinstance(got, OdometryReading)
    np.testing.assert_allclose(got.pose, [1.25, 0.0, 0.125])
    assert buf.at(0.5, 0.5) == "older than the odometry history"
    assert buf.at(3.0, 0.5) == "no odometry within transform_tolerance"
    assert not buf.add(OdometryReading(np.zeros(3), 1.5), max_age=10.0)  # older: refused


def test_a_scan_waits_for_its_odometry_then_is_paired_in_order() -> None:
    pairing, buf = ScanPairing(), _odom(1.0)
    pairing.hold(_scan(1.1), now=0.0)
    pairing.hold(_scan(1.2), now=0.1)
    assert pairing.release(buf, tolerance=1.0, now=0.1) == []  # odometry not there yet
    assert len(pairing) == 2
    buf.add(OdometryReading(np.array([1.15, 0.0, 0.0]), 1.15), max_age=10.0)
    out = pairing.release(buf, tolerance=1.0, now=0.2)
    assert [type(o) for o in out] == [Paired]
    assert out[0].scan.stamp == pytest.approx(1.1)
    assert len(pairing) == 1


def test_a_scan_that_waited_past_the_tolerance_is_given_up_with_the_reason() -> None:
    pairing, buf = ScanPairing(), _odom(1.0)
    pairing.hold(_scan(1.1), now=0.0)
    out = pairing.release(buf, tolerance=1.0, now=1.5)
    assert len(out) == 1
    assert isinstance(out[0], Unpaired)
    assert out[0].reason == NO_ODOM_AT_STAMP
    assert "waited 1.50 s; newest odometry 1.000 s" in out[0].detail
    assert len(pairing) == 0


def test_the_queue_is_bounded() -> None:
    pairing, buf = ScanPairing(max_held=2), _odom(1.0)
    for k in range(3):
        pairing.hold(_scan(1.1 + 0.01 * k), now=None)
    out = pairing.release(buf, tolerance=1.0, now=None)
    assert [type(o) for o in out] == [Unpaired]  # the oldest of three, over the bound of two
    assert len(pairing) == 2
