"""Rates with their uncertainty: the Wilson score interval, and JSON-safe numbers."""

from __future__ import annotations

import math
from typing import Any

__all__ = ["Z95", "json_safe", "wilson_interval"]

Z95 = 1.959963984540054
"""The two-sided 95 % normal quantile."""


def wilson_interval(successes: int, trials: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval ``(low, high)`` of a binomial rate (Wilson 1927).

    ``(0.0, 1.0)`` for zero trials. For 0 successes in n trials the upper bound is about
    ``z^2 / (n + z^2)`` (3.8 / n for large n), the figure to quote for "0 confident wrong".
    """
    if trials < 0 or successes < 0 or successes > trials:
        raise ValueError(
            f"wilson_interval: need 0 <= successes <= trials, got {successes}/{trials}"
        )
    if trials == 0:
        return 0.0, 1.0
    p = successes / trials
    z2 = z * z
    denom = 1.0 + z2 / trials
    centre = (p + z2 / (2 * trials)) / denom
    half = z * math.sqrt(p * (1 - p) / trials + z2 / (4 * trials * trials)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


def json_safe(value: Any) -> Any:
    """``value`` with every non-finite float replaced by None (standard JSON has no NaN)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value
