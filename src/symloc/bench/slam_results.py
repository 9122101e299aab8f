"""The README's SLAM-beside-GMapping table, rendered from a ``bench slam`` results file.

``symloc bench slam ... --results docs/results/NAME.json`` writes the per-log summary of
:func:`symloc.bench.slam_bench.summarize` with its provenance (:mod:`symloc.bench.results_file`);
:class:`SlamFigures` turns it into the Markdown the README shows (:mod:`symloc.readme`), so the
table, the counts of logs where symloc is ahead and the targets cannot drift from the run.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["ON_PAR", "SlamFigures"]

ON_PAR = 0.9
"""Two mean ATEs are on par unless the smaller is below this fraction of the larger."""


def _f(v: Any, spec: str = ".3f") -> str:
    return "-" if v is None else format(v, spec)


class SlamFigures:
    """Figures of one ``bench slam`` results file (``doc``: its parsed JSON)."""

    def __init__(self, doc: Mapping[str, Any]) -> None:
        self.doc = doc
        self.logs: dict[str, dict[str, dict[str, Any]]] = dict(doc["figures"]["logs"])
        self.targets: dict[str, Any] = dict(doc["figures"]["targets"])
        self.peer = next(
            (s for per in self.logs.values() for s in per if s != "symloc"), "gmapping"
        )

    def verdict(self, log: str) -> str:
        """``"symloc"``, ``"peer"`` or ``"par"``: whose mean ATE is clearly lower on ``log``
        (by more than :data:`ON_PAR`), or neither."""
        a = self.logs[log].get("symloc", {}).get("ate_mean_m")
        b = self.logs[log].get(self.peer, {}).get("ate_mean_m")
        if a is None or b is None:
            return "par"
        if a < ON_PAR * b:
            return "symloc"
        if b < ON_PAR * a:
            return "peer"
        return "par"

    def table(self) -> str:
        """The per-log Markdown table (ATE mean / worst / max error per system, peak memory,
        real-time factor, loop closures), the clearly better mean ATE in bold."""
        peer = self.peer
        name = "GMapping" if peer == "gmapping" else peer
        lines = [
            f"| log | symloc ATE mean / worst / max error | {name} ATE mean / worst / max error "
            f"| peak MB symloc / {name} | x real time (CPU) symloc / {name} "
            "| symloc loops accepted / rejected |",
            "| --- | --- | --- | --- | --- | --- |",
        ]
        for log in sorted(self.logs):
            s = self.logs[log].get("symloc", {})
            g = self.logs[log].get(peer, {})
            best = self.verdict(log)

            def ate(e: Mapping[str, Any], bold: bool) -> str:
                mean = _f(e.get("ate_mean_m"))
                mean = f"**{mean}**" if bold else mean
                return f"{mean} / {_f(e.get('ate_worst_m'))} / {_f(e.get('max_error_m'), '.2f')}"

            lines.append(
                f"| {log} | {ate(s, best == 'symloc')} | {ate(g, best == 'peer')} "
                f"| {_f(s.get('peak_rss_mb'), '.0f')} / {_f(g.get('peak_rss_mb'), '.0f')} "
                f"| {_f(s.get('realtime_factor_cpu'), '.0f')} / "
                f"{_f(g.get('realtime_factor_cpu'), '.0f')} "
                f"| {_f(s.get('loops_accepted'), '.0f')} / {_f(s.get('loops_rejected'), '.0f')} |"
            )
        return "\n".join(lines) + "\n"

    def logs_where(self, verdict: str) -> list[str]:
        """The logs (sorted) whose :meth:`verdict` is ``verdict``."""
        return [log for log in sorted(self.logs) if self.verdict(log) == verdict]

    def peak_range(self, system: str) -> str:
        """``"352-679"``: the range of ``system``'s peak memory [MB] over the logs."""
        peaks = [
            e["peak_rss_mb"]
            for per in self.logs.values()
            if (e := per.get(system)) and e.get("peak_rss_mb") is not None
        ]
        return f"{min(peaks):.0f}-{max(peaks):.0f}" if peaks else "-"
