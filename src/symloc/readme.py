"""The README's figures, rendered from results files with cog.

Each figure of the README that a command measured sits in a block between cog markers::

    <!-- [[[cog
    cog.out(localization("bench_localization_test_realistic").table())
    ]]] -->
    | family | trials | ... (rendered: do not edit by hand)
    <!-- [[[end]]] -->

The Python between ``[[[cog`` and ``]]]`` reads a results file under ``docs/results/`` (see
:mod:`symloc.bench.results_file`: command, commit, date, machine, load, settings, figures) and
writes the text below it. ``python -m symloc.readme`` re-renders every block in place;
``python -m symloc.readme --check`` fails, with a diff, when a block differs from what its
results file renders or a results file lacks its provenance (``tests/test_readme_results.py``
runs the check). ``python -m symloc.readme from-bench`` turns a ``bench localization`` JSON
written without a results file into one.
"""

from __future__ import annotations

import argparse
import io
import json
import logging
import sys
from collections.abc import Sequence
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path
from typing import Any

from symloc.bench.experiment_results import (
    AmclSymmetricFigures,
    BenchFigures,
    ExperimentFigures,
    KeyframesFigures,
    Table1Figures,
    Table3Figures,
    expect,
    span,
)
from symloc.bench.localization_results import (
    LocalizationFigures,
    percent,
    wilson_upper,
    write_localization_results,
)
from symloc.bench.results_file import ResultsFileError, load_results
from symloc.bench.slam_results import SlamFigures

__all__ = [
    "RESULTS_DIR",
    "amcl_symmetric",
    "bench",
    "check",
    "expect",
    "experiment",
    "keyframes",
    "localization",
    "main",
    "percent",
    "render",
    "results",
    "results_dir",
    "slam",
    "span",
    "table1",
    "table3",
    "wilson_upper",
]

log = logging.getLogger(__name__)

RESULTS_DIR = Path("docs") / "results"
"""Where the results files live, relative to the README."""


def results_dir() -> Path:
    """``docs/results`` beside the file cog is processing (the README), else under the current
    folder."""
    cog = sys.modules.get("cog")
    in_file = getattr(cog, "inFile", None)
    base = Path(in_file).resolve().parent if in_file else Path.cwd()
    return base / RESULTS_DIR


def results(name: str) -> dict[str, Any]:
    """The results file ``docs/results/NAME.json``, validated (provenance fields present)."""
    return load_results(results_dir() / f"{name}.json")


def localization(name: str) -> LocalizationFigures:
    """The figures of a ``bench localization`` results file."""
    return LocalizationFigures(results(name))


def slam(name: str) -> SlamFigures:
    """The figures of a ``bench slam`` results file."""
    return SlamFigures(results(name))


def experiment(name: str) -> ExperimentFigures:
    """Any ``symloc experiment ... --results`` file: its provenance in words."""
    return ExperimentFigures(results(name))


def bench(name: str) -> BenchFigures:
    """A benchmark script's results file (``python benchmarks/NAME.py --results PATH``): its
    rows and its provenance in words."""
    return BenchFigures(results(name), name)


def table1(name: str = "table1") -> Table1Figures:
    """The figures of a ``symloc experiment table1`` results file."""
    return Table1Figures(results(name))


def table3(name: str = "table3") -> Table3Figures:
    """The figures of a ``symloc experiment table3`` results file."""
    return Table3Figures(results(name))


def amcl_symmetric(name: str = "amcl_symmetric") -> AmclSymmetricFigures:
    """The figures of a ``symloc experiment amcl-symmetric`` results file."""
    return AmclSymmetricFigures(results(name))


def keyframes(name: str = "keyframes") -> KeyframesFigures:
    """The figures of a ``symloc experiment keyframes`` results file."""
    return KeyframesFigures(results(name))


def _cog(argv: Sequence[str]) -> tuple[int, str]:
    try:
        from cogapp import Cog
    except ImportError as err:  # pragma: no cover - cogapp comes with the [test] extra
        raise ResultsFileError(
            "the README's blocks are rendered with cog: pip install cogapp (in the [test] extra)"
        ) from err
    out = io.StringIO()
    cog = Cog()
    cog.set_output(stdout=out, stderr=out)
    with redirect_stdout(out), redirect_stderr(out):
        code = cog.main(["cog", *argv])
    return int(code), out.getvalue()


def _check_all_results(readme: Path) -> list[str]:
    """Problems with the results files beside ``readme``: unreadable, missing provenance, or
    never named in the README."""
    problems: list[str] = []
    folder = readme.resolve().parent / RESULTS_DIR
    text = readme.read_text(encoding="utf-8")
    for path in sorted(folder.glob("*.json")):
        try:
            load_results(path)
        except ResultsFileError as err:
            problems.append(str(err))
        if f'"{path.stem}"' not in text:
            problems.append(f"{path}: not rendered anywhere in {readme.name}")
    return problems


def render(readme: Path) -> str:
    """Re-render every cog block of ``readme`` in place; returns cog's report."""
    code, report = _cog(["-r", str(readme)])
    if code:
        raise ResultsFileError(f"{readme}: cog failed:\n{report}")
    return report


def check(readme: Path) -> tuple[bool, str]:
    """``(True, report)`` when every block of ``readme`` is what its results file renders and
    every results file beside it has its provenance and is used; else ``(False, why)``."""
    problems = _check_all_results(readme)
    try:
        code, report = _cog(["--check", "--diff", str(readme)])
    except ResultsFileError as err:
        return False, str(err)
    if code:
        problems.append(
            f"{readme}: a block differs from what its results file renders "
            f"(re-render: python -m symloc.readme):\n{report}"
        )
    return not problems, "\n".join(problems) if problems else report


def _from_bench(args: argparse.Namespace) -> int:
    doc = json.loads(Path(args.json).read_text(encoding="utf-8"))
    timing: dict[str, Any] = {}
    if args.timing is not None:
        timing = json.loads(Path(args.timing).read_text(encoding="utf-8"))
    path = write_localization_results(
        args.out,
        doc,
        command=args.command,
        commit=args.commit,
        date=args.date,
        machine=args.machine,
        load=args.load,
        workers=timing.get("workers"),
        wall_s=timing.get("wall_s"),
        note=args.note,
    )
    print(f"wrote {path}")
    return 0


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m symloc.readme",
        description="Re-render the README's figure blocks from docs/results/*.json (cog), or "
        "check that they agree.",
    )
    p.add_argument("--readme", type=Path, default=Path("README.md"), help="default README.md")
    p.add_argument("--check", action="store_true", help="change nothing; exit 1 on a difference")
    sub = p.add_subparsers(dest="action")
    fb = sub.add_parser(
        "from-bench",
        help="write a results file from a bench localization JSON made without one",
    )
    fb.add_argument("json", type=Path, help="bench_localization.json")
    fb.add_argument("--timing", type=Path, help="its timing.json (wall time, workers)")
    fb.add_argument("--out", type=Path, required=True, help="docs/results/NAME.json")
    fb.add_argument("--command", required=True, help="the command line that made the JSON")
    fb.add_argument("--commit", required=True)
    fb.add_argument("--date", required=True, help="YYYY-MM-DD")
    fb.add_argument("--machine", required=True, help="e.g. '2 cores, 24 GiB'")
    fb.add_argument("--load", required=True, help="what else ran meanwhile")
    fb.add_argument("--note", default=None)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m symloc.readme [README] [--check]`` and ``... from-bench``."""
    args = _parser().parse_args(argv)
    try:
        if args.action == "from-bench":
            return _from_bench(args)
        if args.check:
            ok, report = check(args.readme)
            print(report if not ok else f"{args.readme}: every block agrees with its results file")
            return 0 if ok else 1
        print(render(args.readme) or f"{args.readme}: re-rendered")
        problems = _check_all_results(args.readme)
        for problem in problems:
            print(f"warning: {problem}", file=sys.stderr)
        return 1 if problems else 0
    except (OSError, ResultsFileError) as err:
        print(f"symloc.readme: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
