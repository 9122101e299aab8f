"""The strict settings checks: a field typed wrong is refused, never converted."""

from __future__ import annotations

import math

import pytest

from symloc._checks import check_integer, exact_real
from symloc.errors import ConfigurationError


@pytest.mark.parametrize("value", [True, "1.5", None, [1.0]])
def test_exact_real_refuses_what_is_not_an_int_or_float(value: object) -> None:
    assert math.isnan(exact_real(value))


def test_exact_real_keeps_numbers() -> None:
    assert exact_real(3) == 3.0
    assert exact_real(0.25) == 0.25
    assert math.isinf(exact_real(math.inf))


@pytest.mark.parametrize("value", [True, 2.0, "3", 1])
def test_check_integer_names_the_field(value: object) -> None:
    with pytest.raises(ConfigurationError, match=r"Settings\.count: expected an integer >= 2"):
        check_integer(value, "Settings.count", 2)


def test_check_integer_returns_the_value() -> None:
    assert check_integer(5, "Settings.count", 2) == 5
