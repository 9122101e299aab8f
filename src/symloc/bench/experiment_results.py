"""The figures of the paper experiments' results files, as the README quotes them.

``symloc experiment table1 | table3 | amcl-symmetric | keyframes --results PATH`` write a results
file (:mod:`symloc.bench.results_file`); the classes here read its ``figures`` and give the
phrases the README's blocks print (:mod:`symloc.readme`): counts as ``"40-50/50"``, the run as
``"6 s wall, commit 19e1cc4, 2026-11-28"``. :func:`expect` checks a figure a sentence states in
words (``"never a wrong claim"``) and raises :class:`FiguresChangedError` when the results file
says otherwise, so the sentence cannot go stale either.
"""

from __future__ import annotations

import datetime as _dt
import logging
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from symloc.bench.localization_results import FiguresChangedError

__all__ = [
    "AmclSymmetricFigures",
    "BenchFigures",
    "ExperimentFigures",
    "KeyframesFigures",
    "Table1Figures",
    "Table3Figures",
    "expect",
    "span",
]

log = logging.getLogger(__name__)


def expect(what: str, found: Any, stated: Any) -> str:
    """Check that a README sentence's figure ``stated`` is what the results file has
    (``found``); raises :class:`FiguresChangedError` naming ``what`` otherwise. Returns ``""``
    so a block can call it inline."""
    if found != stated:
        raise FiguresChangedError(
            f"the README states {stated!r} for {what}; the results file has {found!r}: "
            "rewrite the sentence"
        )
    return ""


def span(values: Iterable[int], of: int | None = None) -> str:
    """``"40-50"`` (or ``"50"`` when all are equal), with ``"/of"`` appended when given."""
    vals = sorted(int(v) for v in values)
    if not vals:
        raise FiguresChangedError("no values to quote: the results file has no such cells")
    text = f"{vals[0]}" if vals[0] == vals[-1] else f"{vals[0]}-{vals[-1]}"
    return f"{text}/{of}" if of is not None else text


class ExperimentFigures:
    """A results file of ``symloc experiment NAME --results``: its provenance in words."""

    def __init__(self, doc: Mapping[str, Any]) -> None:
        self.doc = doc
        self.figures: Mapping[str, Any] = doc["figures"]
        self.settings: Mapping[str, Any] = doc["settings"]

    def __getitem__(self, key: str) -> Any:
        return self.doc[key]

    def run(self, machine: bool = False) -> str:
        """``"6 s wall, commit 19e1cc4, 2026-11-28"``; with ``machine`` the machine and its load
        follow in parentheses."""
        from symloc.bench.results_file import describe_load, describe_machine

        d = self.doc
        wall = d.get("wall_s")
        head = f"{wall:.0f} s wall" if wall is not None else "run"
        text = f"{head}, commit {d['commit']}, {d['date'][:10]}"
        if machine:
            text += f" ({describe_machine(d['machine'])}; {describe_load(d['load'])})"
        return text


class BenchFigures(ExperimentFigures):
    """A results file of a benchmark script (``python benchmarks/NAME.py ... --results PATH``)
    whose ``figures`` hold a list of ``rows`` (one dict per measured line of its table)."""

    def __init__(self, doc: Mapping[str, Any], name: str) -> None:
        super().__init__(doc)
        self.name = name

    def interval(self) -> tuple[_dt.datetime, _dt.datetime] | None:
        """When the run went on (UTC): its ``date`` (the end, to the second) minus its
        ``wall_s``; ``None`` when the file has no time of day or no wall time."""
        d = self.doc
        if len(d["date"]) <= 10 or d.get("wall_s") is None:
            return None
        end = _dt.datetime.fromisoformat(d["date"].replace("Z", "+00:00"))
        return end - _dt.timedelta(seconds=float(d["wall_s"])), end

    def overlaps(self, other: BenchFigures) -> bool:
        """Whether this run and ``other`` went on at the same time (to the second)."""
        a, b = self.interval(), other.interval()
        return a is not None and b is not None and a[0] < b[1] and b[0] < a[1]

    def source(self, beside: Sequence[BenchFigures] = ()) -> str:
        """The run in words for a README paragraph: ``"`python benchmarks/...`, commit 7a9cbc1,
        2026-11-28, 2 cores, ...; load average 0.9 at the start, ...; results file
        [docs/results/NAME.json](docs/results/NAME.json)"``; each run of ``beside`` that went on
        at the same time is named (``"while `python benchmarks/soak_node.py ...` ran"``)."""
        from symloc.bench.results_file import describe_load, describe_machine

        d = self.doc
        path = f"docs/results/{self.name}.json"
        meanwhile = "".join(
            f", while `{o['command']}` ran" for o in beside if o is not self and self.overlaps(o)
        )
        return (
            f"`{d['command']}`, commit {d['commit']}, {d['date'][:10]}, "
            f"{describe_machine(d['machine'])}; {describe_load(d['load'])}{meanwhile}; "
            f"results file [{path}]({path})"
        )

    def rows(self, **match: Any) -> list[Mapping[str, Any]]:
        """The rows whose fields equal ``match``; raises :class:`FiguresChangedError` when
        none does (the README names a row the benchmark no longer measures)."""
        out = [r for r in self.figures["rows"] if all(r.get(k) == v for k, v in match.items())]
        if not out:
            raise FiguresChangedError(f"{self.name}: no row with {match}")
        return out

    def row(self, **match: Any) -> Mapping[str, Any]:
        """The one row matching ``match`` (the first when several do)."""
        return self.rows(**match)[0]


class Table1Figures(ExperimentFigures):
    """``symloc experiment table1``: correct recognitions per (shape, G-V, sensor, method,
    centroid) cell, and false positives on asymmetric rooms."""

    def cells(self, **match: Any) -> list[Mapping[str, Any]]:
        """The cells whose fields equal ``match`` (e.g. ``sensor="lds01", gv=3.0``)."""
        out = [c for c in self.figures["cells"] if all(c[k] == v for k, v in match.items())]
        if not out:
            raise FiguresChangedError(f"table1: no cell with {match}")
        return out

    def correct(self, **match: Any) -> list[int]:
        return [int(c["correct"]) for c in self.cells(**match)]

    def counts(self, **match: Any) -> str:
        """The correct recognitions of the matching cells: ``"40-50/50"``."""
        cells = self.cells(**match)
        return span((c["correct"] for c in cells), int(cells[0]["trials"]))

    def all_full(self, **match: Any) -> bool:
        """Every matching cell correct in all its trials."""
        return all(c["correct"] == c["trials"] for c in self.cells(**match))

    def wrong(self, **match: Any) -> int:
        """Verdicts that are neither correct nor "unknown" in the matching cells."""
        return sum(c["trials"] - c["correct"] - c["unknown"] for c in self.cells(**match))

    def false_positives(self) -> tuple[int, int]:
        """``(false positives, scans)`` of the area centroid on the asymmetric rooms."""
        fp = self.figures["false_positives"]
        return int(fp["count"]), int(fp["trials"])


class Table3Figures(ExperimentFigures):
    """``symloc experiment table3``: the BoW similarity matrix and the orientation decisions."""

    def _matrix(self) -> list[list[float]]:
        return [list(row) for row in self.figures["similarity"]]

    def diagonal(self) -> tuple[float, float]:
        m = self._matrix()
        vals = [m[i][i] for i in range(len(m))]
        return min(vals), max(vals)

    def off_diagonal(self) -> tuple[float, float]:
        m = self._matrix()
        vals = [m[i][j] for i in range(len(m)) for j in range(len(m)) if i != j]
        return min(vals), max(vals)

    def ratio(self) -> tuple[float, float]:
        """Each row's diagonal over its largest off-diagonal value: ``(min, max)`` over rows."""
        m = self._matrix()
        rows = [m[i][i] / max(m[i][j] for j in range(len(m)) if j != i) for i in range(len(m))]
        return min(rows), max(rows)

    def counts(self, which: str = "counts") -> Mapping[str, int]:
        """``counts`` (textured lab), ``untextured`` or ``untextured_sensitive_orb``."""
        counts: Mapping[str, int] = self.figures[which]
        return counts


class AmclSymmetricFigures(ExperimentFigures):
    """``symloc experiment amcl-symmetric``: plain AMCL's end state per room."""

    def room(self, name: str) -> Mapping[str, Any]:
        for r in self.rooms():
            if r["room"] == name:
                return r
        raise FiguresChangedError(f"amcl-symmetric: no room {name!r} in the results file")

    def rooms(self) -> Sequence[Mapping[str, Any]]:
        rooms: Sequence[Mapping[str, Any]] = self.figures["rooms"]
        return rooms


class KeyframesFigures(ExperimentFigures):
    """``symloc experiment keyframes``: images and bytes stored per policy."""

    def policies(self) -> Sequence[Mapping[str, Any]]:
        policies: Sequence[Mapping[str, Any]] = self.figures["policies"]
        return policies

    def ratio(self, key: str = "bytes_features") -> float:
        a, b = self.policies()[0], self.policies()[1]
        return float(b[key]) / float(a[key])
