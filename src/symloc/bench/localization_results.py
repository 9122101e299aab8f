"""``symloc bench localization`` as a results file, and the README's figures rendered from it.

:func:`compact_figures` keeps, of the bench's JSON (``bench_localization.json``, megabytes with
every trial), the per family and method summary rows (the output of
:func:`symloc.bench.localization.summarize`) with the counts, intervals and medians the README
quotes. :class:`LocalizationFigures` reads them back: the three-method table
(:meth:`~LocalizationFigures.table`) and the formatted figures the README's sentences use.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from symloc.bench.stats import wilson_interval

__all__ = [
    "SUMMARY_FIELDS",
    "FiguresChangedError",
    "LocalizationFigures",
    "Row",
    "compact_figures",
    "percent",
    "wilson_upper",
]

SUMMARY_FIELDS = (
    "family",
    "method",
    "trials",
    "correct",
    "confident_wrong",
    "undetermined",
    "correct_ci95",
    "confident_wrong_ci95",
    "median_time_to_claim_s",
    "median_distance_to_claim_m",
    "tracking_error_p95_m",
    "covariance_coverage",
    "heading_correct",
    "heading_wrong",
)
"""The fields of a summary row that a results file keeps."""

LABELS = {
    "symloc": "symloc (as shipped)",
    "centre": "the paper's path (centre)",
    "amcl": "plain AMCL",
    "decide": "deciding here (forced)",
}
SHORT = {"symloc": "symloc", "centre": "centre", "amcl": "AMCL", "decide": "decide"}


def compact_figures(summary: Iterable[Mapping[str, Any]]) -> dict[str, Any]:
    """The ``figures`` of a results file from a bench summary (``doc["summary"]``): each row
    reduced to :data:`SUMMARY_FIELDS`, families in alphabetical order with ``all`` last."""
    rows = [{k: row.get(k) for k in SUMMARY_FIELDS} for row in summary]
    rows.sort(key=lambda r: (r["family"] == "all", r["family"], r["method"]))
    return {"summary": rows}


def percent(k: int, n: int, digits: int = 0) -> str:
    """``k`` of ``n`` as a percentage with ``digits`` decimals (``"-"`` for ``n == 0``)."""
    return f"{100 * k / n:.{digits}f}" if n else "-"


def wilson_upper(k: int, n: int, digits: int = 1) -> str:
    """The upper Wilson 95 % bound of ``k`` of ``n``, in per cent."""
    return f"{100 * wilson_interval(k, n)[1]:.{digits}f}"


def _finite(value: Any) -> float | None:
    if value is None:
        return None
    x = float(value)
    return x if math.isfinite(x) else None


@dataclass(frozen=True)
class Row:
    """One family and method of a results file, formatted as the README quotes it."""

    data: Mapping[str, Any]

    def __getitem__(self, key: str) -> Any:
        return self.data[key]

    @property
    def n(self) -> int:
        """Trials in this row."""
        return int(self.data["trials"])

    def pct(self, key: str, digits: int = 0) -> str:
        """The count ``key`` (``correct``, ``confident_wrong``, ...) in per cent of the trials."""
        return percent(int(self.data[key]), self.n, digits)

    def ci(self, key: str, digits: int = 0, sep: str = "-") -> str:
        """The Wilson 95 % interval of ``key`` in per cent, ``"62-73"``."""
        lo, hi = self.data[f"{key}_ci95"]
        return f"{100 * lo:.{digits}f}{sep}{100 * hi:.{digits}f}"

    def upper(self, key: str, digits: int = 1) -> str:
        """The upper Wilson 95 % bound of ``key`` in per cent."""
        return f"{100 * self.data[f'{key}_ci95'][1]:.{digits}f}"

    def cell(self) -> str:
        """``correct / **confident wrong** [95 % CI] / undetermined`` in per cent."""
        return (
            f"{self.pct('correct')} / **{self.pct('confident_wrong', 1)}** "
            f"[{self.ci('confident_wrong', 1, ', ')}] / {self.pct('undetermined')}"
        )

    def claim(self, sep: str = ", ") -> str:
        """Median time and distance to the first claim, ``"2.7 s, 0.36 m"`` (``"-"``: none)."""
        t = _finite(self.data["median_time_to_claim_s"])
        d = _finite(self.data["median_distance_to_claim_m"])
        if t is None or d is None:
            return "-"
        return f"{t:.1f} s{sep}{d:.2f} m"

    def coverage(self, digits: int = 2) -> str:
        """Covariance coverage of the claims (``"-"`` when nothing was claimed)."""
        c = _finite(self.data["covariance_coverage"])
        return "-" if c is None else f"{c:.{digits}f}"


class FiguresChangedError(AssertionError):
    """A README sentence that names families no longer matches its results file."""


class LocalizationFigures:
    """The figures of a ``bench localization`` results file (see :mod:`symloc.bench.results_file`)."""

    def __init__(self, doc: Mapping[str, Any]) -> None:
        self.doc = doc
        rows = doc["figures"]["summary"]
        self._rows = {(r["family"], r["method"]): Row(r) for r in rows}
        present = list(dict.fromkeys(r["method"] for r in rows))
        ordered = [m for m in doc.get("settings", {}).get("methods", []) if m in present]
        self.methods: list[str] = ordered + [m for m in present if m not in ordered]
        """The methods in the order the command was given them."""
        self.families: list[str] = sorted({r["family"] for r in rows if r["family"] != "all"})

    def row(self, family: str, method: str) -> Row:
        """The row of ``family`` (or ``"all"``) and ``method``; KeyError names what exists."""
        try:
            return self._rows[(family, method)]
        except KeyError:
            raise KeyError(
                f"no row {family!r}/{method!r}: families {[*self.families, 'all']}, "
                f"methods {self.methods}"
            ) from None

    def __getitem__(self, key: str) -> Any:
        return self.doc[key]

    def where(self, method: str, test: Callable[[Row], bool]) -> list[str]:
        """The families (alphabetical) whose row of ``method`` passes ``test``."""
        return [f for f in self.families if test(self.row(f, method))]

    def expect(self, method: str, key: str, counts: Mapping[str, int]) -> str:
        """Check a sentence that names families: the families whose ``method`` row has ``key``
        above 0 are exactly those of ``counts``, with those counts. Raises
        :class:`FiguresChangedError` (the sentence needs rewriting) otherwise; returns ``""`` so a
        README block can call it inline."""
        found = {f: int(self.row(f, method)[key]) for f in self.families}
        found = {f: k for f, k in found.items() if k > 0}
        if found != dict(counts):
            raise FiguresChangedError(
                f"{self.doc.get('command')}: the README names {dict(counts)} as the families with "
                f"{key} ({method}); the results file has {found}: rewrite the sentence"
            )
        return ""

    def run(self, machine: bool = True) -> str:
        """How the run went, for a README: ``"958 s wall on 2 workers (commit 1854f5b,
        2026-11-28; MACHINE; LOAD)"``, or without the machine and its load
        ``"313 s wall on 2 workers, commit 1854f5b, 2026-11-28"``."""
        from symloc.bench.results_file import describe_load, describe_machine

        d = self.doc
        wall = d.get("wall_s")
        workers = d.get("workers")
        plural = "" if workers == 1 else "s"
        head = f"{wall:.0f} s wall on {workers} worker{plural}" if wall is not None else "run"
        when = f"commit {d['commit']}, {d['date'][:10]}"
        if not machine:
            return f"{head}, {when}"
        return f"{head} ({when}; {describe_machine(d['machine'])}; {describe_load(d['load'])})"

    def table(self, methods: Sequence[str] | None = None) -> str:
        """The Markdown table: per family, each method's correct / confident wrong [95 % CI] /
        undetermined in per cent, and the median time and distance to the first claim."""
        ms = list(methods or self.methods)
        first = (
            f"{LABELS.get(ms[0], ms[0])}: correct / **confident wrong** [95 % CI] / undetermined %"
        )
        heads = [first, *(LABELS.get(m, m) for m in ms[1:])]
        timing = "time to localize (median time, distance to first claim): " + " / ".join(
            SHORT.get(m, m) for m in ms
        )
        cols = ["family", "trials", *heads, timing]
        lines = ["| " + " | ".join(cols) + " |", "|" + " --- |" * len(cols)]
        for family in [*self.families, "all"]:
            rows = [self.row(family, m) for m in ms]
            name = "**all**" if family == "all" else family
            cells = [name, str(rows[0].n), *(r.cell() for r in rows)]
            cells.append(" / ".join(r.claim() for r in rows))
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines) + "\n"


def write_localization_results(
    path: Any,
    doc: Mapping[str, Any],
    *,
    command: str,
    commit: str,
    date: str,
    machine: Mapping[str, Any] | str,
    load: Mapping[str, Any] | str,
    workers: int | None,
    wall_s: float | None,
    note: str | None = None,
) -> Any:
    """Write the results file of a ``bench localization`` run: its JSON ``doc`` (settings and
    summary) reduced by :func:`compact_figures`, with the provenance given. Returns the path."""
    from symloc.bench.results_file import write_results

    extra: dict[str, Any] = {
        "workers": workers,
        "wall_s": None if wall_s is None else round(wall_s, 1),
    }
    if note:
        extra["note"] = note
    return write_results(
        path,
        command=command,
        commit=commit,
        date=date,
        machine=machine,
        load=load,
        settings=dict(doc["settings"]),
        figures=compact_figures(doc["summary"]),
        **extra,
    )
