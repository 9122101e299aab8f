from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from symloc.errors import DataFormatError
from symloc.geometry import angle_diff
from symloc.odometry import OdometryIncrement, OdometryReading, rot_trans_rot, rot_trans_rot_to_pose

pose_st = st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-np.pi, np.pi)).map(np.array)


def test_increment_hand_computed() -> None:
    a = OdometryReading(np.array([1.0, 1.0, np.pi / 2]), stamp=1.0)
    b = OdometryReading(np.array([1.0, 2.0, np.pi]), stamp=1.5)
    inc = OdometryIncrement.between(a, b)
    np.testing.assert_allclose(inc.delta, [1.0, 0.0, np.pi / 2], atol=1e-12)
    assert inc.rot1 == pytest.approx(0.0)
    assert inc.trans == pytest.approx(1.0)
    assert inc.rot2 == pytest.approx(np.pi / 2)
    assert inc.dt == pytest.approx(0.5)


@given(pose_st, pose_st)
def test_rot_trans_rot_round_trip(a: np.ndarray, b: np.ndarray) -> None:
    r1, tr, r2 = rot_trans_rot(a, b)
    back = rot_trans_rot_to_pose(a, r1, tr, r2)
    if tr >= 0.01:
        np.testing.assert_allclose(back[:2], b[:2], atol=1e-6)
    assert abs(angle_diff(back[2], b[2])) < 1e-9


def test_reading_rejects_nan_and_bad_shape() -> None:
    with pytest.raises(DataFormatError, match=r"pose: expected finite values"):
        OdometryReading(np.array([0.0, np.nan, 0.0]))
    with pytest.raises(DataFormatError, match=r"pose: expected shape \(3,\)"):
        OdometryReading(np.zeros(2))
    with pytest.raises(DataFormatError, match="stamp"):
        OdometryReading(np.zeros(3), stamp=float("inf"))
