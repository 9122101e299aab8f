"""Small validation helpers called at the top of public functions.

Each one converts, validates and returns, and names the offending argument in its message.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError

__all__ = [
    "as_rng",
    "check_array",
    "check_finite_scalar",
    "check_in_range",
    "check_integer",
    "check_positive",
    "exact_real",
]


def as_rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    """Return a Generator from a Generator, an integer seed, or None (fresh entropy)."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, (int, np.integer)):
        return np.random.default_rng(rng)
    raise ConfigurationError(f"rng: expected a numpy Generator, an int seed or None, got {rng!r}")


def check_finite_scalar(value: Any, name: str) -> float:
    """Return ``value`` as a float, raising if it is not a finite real number."""
    try:
        out = float(value)
    except (TypeError, ValueError) as err:
        raise ConfigurationError(f"{name}: expected a real number, got {value!r}") from err
    if not math.isfinite(out):
        raise ConfigurationError(f"{name}: expected a finite number, got {out}")
    return out


def check_positive(value: Any, name: str, *, allow_zero: bool = False) -> float:
    """Return ``value`` as a finite float that is > 0 (or >= 0 with ``allow_zero``)."""
    out = check_finite_scalar(value, name)
    if out < 0 or (out == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ConfigurationError(f"{name}: expected a value {bound}, got {out}")
    return out


def exact_real(value: Any) -> float:
    """``value`` as a float when it is an int or a float (not a bool, not a numeric string:
    a settings field typed wrong is refused, not converted); NaN otherwise, which fails every
    range test."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return math.nan
    return float(value)


def check_integer(value: Any, name: str, low: int) -> int:
    """Return ``value`` when it is an int (not a bool) >= ``low``."""
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise ConfigurationError(f"{name}: expected an integer >= {low}, got {value!r}")
    return value


def check_in_range(value: Any, name: str, low: float, high: float) -> float:
    """Return ``value`` as a finite float in the closed interval [low, high]."""
    out = check_finite_scalar(value, name)
    if not low <= out <= high:
        raise ConfigurationError(f"{name}: expected a value in [{low}, {high}], got {out}")
    return out


def check_array(
    value: ArrayLike,
    name: str,
    *,
    shape: tuple[int | None, ...],
    finite: bool = True,
    dtype: type = np.float64,
) -> NDArray[Any]:
    """Convert ``value`` to an array of ``dtype`` and check its shape.

    ``shape`` uses ``None`` for a free dimension, e.g. ``(None, 3)`` for N poses.
    """
    try:
        arr: NDArray[Any] = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as err:
        raise ConfigurationError(f"{name}: cannot convert to an array of {dtype.__name__}") from err
    if arr.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(arr.shape, shape, strict=True)
    ):
        want_s = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise ConfigurationError(f"{name}: expected shape {want_s}, got {arr.shape}")
    if finite and arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
        raise ConfigurationError(f"{name}: contains NaN or infinite values")
    return arr
