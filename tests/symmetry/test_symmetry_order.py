"""SymmetryOrder: a finite k >= 1 or a circle; "unknown" is None, never an order."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.symmetry import SymmetryOrder


def test_finite_and_circle() -> None:
    four = SymmetryOrder.finite(4)
    assert four.k == 4
    assert not four.is_circle
    assert four.symmetric
    assert four.step == pytest.approx(math.pi / 2)
    assert four.copies(8) == 4
    assert str(four) == "4"
    circle = SymmetryOrder.CIRCLE
    assert circle.k is None
    assert circle.is_circle
    assert circle.symmetric
    assert circle.step is None
    assert circle.copies(8) == 8
    assert str(circle) == "inf"
    assert f"(order {circle})" == "(order inf)"
    assert not SymmetryOrder.finite(1).symmetric
    assert circle != SymmetryOrder.finite(1)
    assert SymmetryOrder(None) == circle
    assert len({SymmetryOrder.finite(2), SymmetryOrder.finite(2), circle}) == 2


def test_numpy_integers_are_plain_ints() -> None:
    k = SymmetryOrder.finite(np.int64(6))  # type: ignore[arg-type]
    assert type(k.k) is int
    assert k == SymmetryOrder.finite(6)


@pytest.mark.parametrize("bad", [0, -1, 2.0, math.inf, True, "4"])
def test_bad_orders_raise(bad: object) -> None:
    with pytest.raises(ConfigurationError, match="expected an integer k >= 1"):
        SymmetryOrder(bad)  # type: ignore[arg-type]


@given(st.one_of(st.none(), st.integers(1, 10_000)))
def test_json_round_trip(k: int | None) -> None:
    order = SymmetryOrder(k)
    text = json.dumps(order.to_json())
    assert text == ('"inf"' if k is None else str(k))
    assert SymmetryOrder.from_json(json.loads(text)) == order


@pytest.mark.parametrize("bad", [0, "4", 4.0, None, True])
def test_from_json_rejects(bad: object) -> None:
    with pytest.raises(ConfigurationError):
        SymmetryOrder.from_json(bad)


def test_frozen() -> None:
    with pytest.raises(AttributeError):
        SymmetryOrder.CIRCLE.k = 3  # type: ignore[misc]
