"""Helpers every experiment shares: the common options, printing the configuration, JSON."""

from __future__ import annotations

import sys
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from symloc.cli import options

if TYPE_CHECKING:
    import argparse

    from symloc.bench.provenance import RunClock

__all__ = ["add_common_arguments", "print_config", "write_json", "write_results_file"]


def add_common_arguments(parser: Any, name: str) -> None:
    """Add ``--seed``, ``--json`` and ``--out`` (the folder for figures, default
    ``symloc-experiment-<name>``) to the parser of experiment ``name``
    (:mod:`symloc.cli.options`)."""
    options.add_seed(parser)
    options.add_json(parser)
    options.add_out(parser, f"experiment {name}", what="figures")


def print_config(name: str, config: Mapping[str, Any]) -> None:
    """Print an experiment's name, seed and configuration so a run can be reproduced."""
    print(f"# symloc experiment {name}")
    for key, value in config.items():
        print(f"#   {key}: {value}")
    sys.stdout.flush()


def write_json(path: Path | None, data: Mapping[str, Any]) -> None:
    """Write ``data`` as standard JSON (``null`` for NaN) to ``path``; no-op for None."""
    if path is None:
        return
    options.write_json(path, data)
    print(f"wrote {path}")


def write_results_file(
    args: argparse.Namespace,
    clock: RunClock,
    settings: Mapping[str, Any],
    figures: Mapping[str, Any],
    *,
    workers: int = 1,
) -> None:
    """Write the run's results file to ``args.results`` (``--results PATH``; no-op without
    it): ``figures`` with ``settings`` (seed and configuration), the command line, the commit
    the ``clock`` started on, the date, this machine, the load and the wall time
    (:func:`symloc.bench.results_file.write_run_results`)."""
    if getattr(args, "results", None) is None:
        return
    from symloc.bench.results_file import write_run_results

    written = write_run_results(
        args.results,
        argv=getattr(args, "argv", []),
        clock=clock,
        settings=settings,
        figures=figures,
        workers=workers,
    )
    print(f"wrote {written}")
