"""The README's SLAM table rendered from a ``bench slam`` results file (symloc.bench.slam_results)."""

from __future__ import annotations

from typing import Any

from symloc.bench.slam_results import SlamFigures


def _doc(logs: dict[str, tuple[float | None, float | None]]) -> dict[str, Any]:
    def system(ate: float | None, mb: float) -> dict[str, Any]:
        return {
            "ate_mean_m": ate,
            "ate_worst_m": None if ate is None else ate * 1.1,
            "max_error_m": None if ate is None else ate * 3,
            "peak_rss_mb": mb,
            "realtime_factor_cpu": None,
            "loops_accepted": 10.0,
            "loops_rejected": 2.0,
        }

    return {
        "figures": {
            "logs": {
                lg: {"symloc": system(a, 400.0 + i), "gmapping": system(b, 60.0 + i)}
                for i, (lg, (a, b)) in enumerate(logs.items())
            },
            "targets": {},
        }
    }


def test_the_clearly_lower_ate_is_bold_and_near_ties_are_on_par() -> None:
    f = SlamFigures(
        _doc({"a": (0.05, 0.10), "b": (0.30, 0.10), "c": (0.095, 0.10), "d": (None, 0.1)})
    )
    assert [f.verdict(x) for x in "abcd"] == ["symloc", "peer", "par", "par"]
    assert f.logs_where("par") == ["c", "d"]
    rows = f.table().splitlines()
    assert rows[0].startswith("| log | symloc ATE")
    assert "GMapping ATE" in rows[0]
    assert rows[2].startswith("| a | **0.050** / 0.055 / 0.15 | 0.100 / ")
    assert "| **0.100** / 0.110 / 0.30 |" in rows[3]
    assert "**" not in rows[4]
    assert "**" not in rows[5]
    assert "| - / - / - |" in rows[5]
    assert f.peak_range("symloc") == "400-403"
    assert f.peak_range("gmapping") == "60-63"
