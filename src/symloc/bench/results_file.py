"""Results files: a measurement's figures with the provenance that makes them quotable.

A results file is a small JSON document (``docs/results/*.json`` for the README's figures) that
holds what a reader needs to trust and redo a figure: the ``command`` that measured it, the
``commit`` it ran on, the ``date``, the ``machine`` and its ``load``, the ``settings`` (seeds and
configuration) and the ``figures`` themselves. :func:`load_results` refuses a file that lacks any
of them, so a README block rendered from it (:mod:`symloc.readme`) always has them.
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from symloc.bench.stats import json_safe
from symloc.errors import DataFormatError

__all__ = [
    "PROVENANCE",
    "SCHEMA",
    "ResultsFileError",
    "dumps",
    "load_results",
    "validate",
    "write_bench_results",
    "write_results",
    "write_run_results",
]

if TYPE_CHECKING:
    from symloc.bench.provenance import RunClock

log = logging.getLogger(__name__)

SCHEMA = "symloc-results/1"
"""The value of a results file's ``schema`` field."""

PROVENANCE = ("command", "commit", "date", "machine", "load", "settings")
"""Fields every results file must fill in, besides ``figures``."""


class ResultsFileError(DataFormatError):
    """A results file that cannot be read or lacks a provenance field."""


def _missing(value: Any) -> bool:
    return value is None or (isinstance(value, str | Mapping | list) and len(value) == 0)


def validate(doc: Mapping[str, Any], where: str = "results") -> None:
    """Raise :class:`ResultsFileError` naming every provenance field ``doc`` lacks (or leaves
    empty), a ``schema`` other than :data:`SCHEMA`, missing ``figures``, or a ``date`` that is not
    an ISO 8601 date (``2026-11-28``, optionally with a time)."""
    problems = [f"no {key!r}" for key in (*PROVENANCE, "figures") if _missing(doc.get(key))]
    if doc.get("schema") != SCHEMA:
        problems.append(f"schema {doc.get('schema')!r}, expected {SCHEMA!r}")
    date = doc.get("date")
    if isinstance(date, str) and date:
        try:
            _dt.date.fromisoformat(date[:10])
        except ValueError:
            problems.append(f"date {date!r} is not YYYY-MM-DD")
    elif not _missing(date):
        problems.append(f"date {date!r} is not a string")
    if problems:
        raise ResultsFileError(f"{where}: " + "; ".join(problems))


def describe_machine(machine: Mapping[str, Any] | str) -> str:
    """A results file's ``machine`` in words: ``"2 cores, 23.4 GiB, x86_64, Linux 6.1, Python
    3.11.7"`` (a string is given back as written)."""
    if isinstance(machine, str):
        return machine
    parts = [
        f"{machine.get('cpus')} cores",
        f"{machine.get('memory_gib')} GiB",
        machine.get("processor"),
        machine.get("system"),
        f"Python {machine.get('python')}",
    ]
    return ", ".join(str(p) for p in parts if p)


def describe_load(load: Mapping[str, Any] | str) -> str:
    """A results file's ``load`` in words: ``"load average 0.4 at the start, 2.1 at the end, on
    2 cores"`` (a string is given back as written)."""
    if isinstance(load, str):
        return load
    text = (
        f"load average {load.get('load_1min_start')} at the start, "
        f"{load.get('load_1min_end')} at the end"
    )
    if load.get("cpus"):
        text += f", on {load['cpus']} cores"
    note = load.get("note")
    return f"{text}, {note}" if note else text


def load_results(path: str | Path) -> dict[str, Any]:
    """Read and validate a results file; raises :class:`ResultsFileError`."""
    p = Path(path)
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise ResultsFileError(f"{p}: cannot read a results file ({err})") from err
    if not isinstance(doc, dict):
        raise ResultsFileError(f"{p}: a results file is a JSON object")
    validate(doc, str(p))
    return doc


def _flat(value: Any) -> bool:
    """A list or object of scalars (or of lists of scalars): written on one line."""
    items = value.values() if isinstance(value, dict) else value
    return all(
        not isinstance(v, dict | list) or (isinstance(v, list) and not _nested(v)) for v in items
    )


def _nested(value: list[Any]) -> bool:
    return any(isinstance(v, dict | list) for v in value)


def dumps(value: Any, indent: int = 0) -> str:
    """JSON without NaN, one line for each flat object or list (a summary row, a list of seeds)
    in its own key order, and sorted keys indented by one space a level otherwise: short and
    easy to diff."""
    if not isinstance(value, dict | list) or _flat(value):
        return json.dumps(value, allow_nan=False, ensure_ascii=False)
    pad = " " * (indent + 1)
    if isinstance(value, dict):
        items = [f"{pad}{json.dumps(k)}: {dumps(value[k], indent + 1)}" for k in sorted(value)]
        return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"
    items = [f"{pad}{dumps(v, indent + 1)}" for v in value]
    return "[\n" + ",\n".join(items) + "\n" + " " * indent + "]"


def write_results(
    path: str | Path,
    *,
    command: str,
    commit: str,
    date: str,
    machine: Mapping[str, Any] | str,
    load: Mapping[str, Any] | str,
    settings: Mapping[str, Any],
    figures: Mapping[str, Any],
    **extra: Any,
) -> Path:
    """Validate and write a results file (sorted keys, one-space indent, no NaN: null);
    ``extra`` adds fields such as ``workers``, ``wall_s`` or ``note``. Returns ``path``."""
    from symloc.files.atomic import atomic_write_text

    doc: dict[str, Any] = {
        "schema": SCHEMA,
        "command": command,
        "commit": commit,
        "date": date,
        "machine": machine,
        "load": load,
        "settings": settings,
        "figures": figures,
        **extra,
    }
    doc = json_safe(doc)
    validate(doc, str(path))
    out = atomic_write_text(Path(path), dumps(doc) + "\n")
    log.info("wrote results file %s", out)
    return out


def write_run_results(
    path: str | Path,
    *,
    argv: Sequence[str],
    clock: RunClock,
    settings: Mapping[str, Any],
    figures: Mapping[str, Any],
    program: str = "symloc",
    **extra: Any,
) -> Path:
    """Write the results file of a run of this process: the command from ``argv`` (the words
    after ``program``: ``symloc`` for the CLI, ``python`` for a benchmark script given its own
    ``sys.argv``), the commit when the ``clock`` started, the date it stopped, this machine and
    the load around the run, and its wall time."""
    from symloc.bench.provenance import command_line, machine

    clock.stop()
    return write_results(
        path,
        command=command_line(argv, program),
        commit=clock.revision,
        date=clock.finished or clock.started,
        machine=machine(),
        load=clock.load(),
        settings=settings,
        figures=figures,
        wall_s=None if clock.wall_s is None else round(clock.wall_s, 1),
        **extra,
    )


def write_bench_results(
    path: str | Path,
    *,
    clock: RunClock,
    settings: Mapping[str, Any],
    figures: Mapping[str, Any],
    argv: Sequence[str] | None = None,
    **extra: Any,
) -> Path:
    """Write the results file of a benchmark script run as ``python benchmarks/NAME.py ...``:
    :func:`write_run_results` with the script's own ``argv`` (default ``sys.argv``), and when
    the process may only run on some of the machine's cores (``taskset``) the command starts
    with ``taskset -c CPUS`` and ``settings`` gain ``cpus_allowed`` (the core numbers)."""
    import sys

    from symloc.bench.provenance import cpus_allowed

    words = list(sys.argv if argv is None else argv)
    allowed = cpus_allowed()
    program = "python"
    settings = dict(settings)
    if allowed is not None:
        words = ["-c", ",".join(str(c) for c in allowed), "python", *words]
        program = "taskset"
        settings["cpus_allowed"] = allowed
    return write_run_results(
        path, argv=words, clock=clock, settings=settings, figures=figures, program=program, **extra
    )
