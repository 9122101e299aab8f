"""Entry point of the ``symloc`` command.

Sub-commands are discovered, not listed: every module in :mod:`symloc.cli.commands` that defines
``register(subparsers)`` adds its own sub-command, and every module in
:mod:`symloc.experiments` that defines ``register(subparsers)`` adds a ``symloc experiment``
sub-command. A sub-command's parser sets ``func(args) -> int`` as its default.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from collections.abc import Sequence
from types import ModuleType

from symloc import __version__
from symloc.errors import SymlocError
from symloc.runtime import configure_process

__all__ = ["build_parser", "discover", "main"]


def discover(package: str) -> list[ModuleType]:
    """Import every module of ``package`` that defines ``register``, sorted by name."""
    pkg = importlib.import_module(package)
    modules = []
    for info in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{package}.{info.name}")
        if hasattr(module, "register"):
            modules.append(module)
    return modules


def build_parser() -> argparse.ArgumentParser:
    """The full ``symloc`` argument parser."""
    parser = argparse.ArgumentParser(
        prog="symloc",
        description="Localize a robot in symmetric rooms: laser symmetry judgement, AMCL and "
        "visual orientation.",
    )
    parser.add_argument("--version", action="version", version=f"symloc {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for module in discover("symloc.cli.commands"):
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``symloc`` command; returns the process exit code."""
    configure_process()  # before the commands import NumPy (see symloc.runtime)
    parser = build_parser()
    args = parser.parse_args(argv)
    # the command line as given, for the provenance of the results files a command writes
    args.argv = list(sys.argv[1:] if argv is None else argv)
    try:
        code: int = args.func(args)
    except SymlocError as err:
        print(f"symloc: error: {err}", file=sys.stderr)
        return 2
    except OSError as err:
        # the file system refused something the checks before the work could not foresee (a
        # disk that filled up, a read-only mount, a path removed meanwhile): said, not a traceback
        where = f"{err.filename}: " if err.filename else ""
        print(f"symloc: error: {where}{err.strerror or err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("symloc: interrupted", file=sys.stderr)
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
