"""One vocabulary for every ``symloc`` command: shared options, units, numbering, JSON.

Every command (``symloc.cli.commands``, ``symloc.experiments``, ``symloc.cli.bench_commands``)
adds the options it shares with others through the functions here, so a name means the same
thing with the same default, validation and help everywhere (``tests/test_cli_vocabulary.py``
walks the whole parser tree and checks it):

==============  ===========================================================================
option          meaning
==============  ===========================================================================
``--seed N``    random seed, an integer >= 0, default 0; every command prints it
``--out DIR``   the folder the command writes into (created), default ``symloc-<command>``
                (e.g. ``symloc-demo``, ``symloc-experiment-table1``); never a file or prefix
``--json PATH`` also write the results as standard JSON (``null``, never ``NaN``)
``--lidar``     a simulated lidar preset (``lds01``, ``paper_15m``, ``rplidar_a2``), default
                ``rplidar_a2`` (the paper's RPLIDAR A2); sweeps take several or ``all``
``--room``      a simulated room (:data:`ROOMS`), default ``square``
``--trials N``  an integer >= 1 (each command's default is in its help)
==============  ===========================================================================

Units and numbering for people: angles are **degrees** at the command line and in printed
text, radians in the library (:func:`add_angle` converts, and says so in ``--help``);
directions of a place are numbered **1..M** for people (:func:`direction_text`), 0..M-1 in
the library; a circle's symmetry order prints as ``inf`` (:func:`order_text`).

Validation lives in the ``argparse`` types below (:func:`nonnegative_int`,
:func:`positive_int`, :func:`positive_float`, :func:`finite_float`): a bad value is a usage
error naming the option, exit code 2, never a traceback.

A command adopts the vocabulary by calling, in its ``register``::

    from symloc.cli import options

    def register(subparsers):
        p = subparsers.add_parser("demo", help=...)
        options.add_seed(p)
        options.add_out(p, "demo")            # default folder symloc-demo
        options.add_json(p)
        options.add_lidar(p)                  # or add_lidars(p) for a sweep
        options.add_room(p)
        options.add_trials(p, default=100, what="trials per room")
        options.add_angle(p, "--max-yaw", default=5.0, help="largest camera yaw")
        p.set_defaults(func=run)

and, when it writes JSON, :func:`write_json`.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from symloc.lidar_spec import PRESETS
from symloc.symmetry.order import SymmetryOrder

__all__ = [
    "DEFAULT_LIDAR",
    "DEFAULT_ROOM",
    "DEFAULT_SEED",
    "ROOMS",
    "add_angle",
    "add_json",
    "add_lidar",
    "add_lidars",
    "add_out",
    "add_room",
    "add_rooms",
    "add_seed",
    "add_trials",
    "default_out",
    "direction_text",
    "finite_float",
    "json_safe",
    "lidar_names",
    "nonnegative_int",
    "order_text",
    "positive_float",
    "positive_int",
    "refuse_overwriting_inputs",
    "room_names",
    "write_json",
]

DEFAULT_SEED = 0
#: The paper's lidar (Slamtec RPLIDAR A2).
DEFAULT_LIDAR = "rplidar_a2"
DEFAULT_ROOM = "square"
#: Rooms of the simulator a command can build (``symloc.sim.rooms.build_room`` names, plus the
#: 40 m hallway whose ends the lidar cannot see).
ROOMS = (
    "triangle",
    "square",
    "pentagon",
    "hexagon",
    "octagon",
    "circle",
    "rectangle",
    "hallway",
    "hallway_40m",
    "l_shaped",
)
LIDARS = tuple(sorted(PRESETS))


# ----------------------------------------------------------------------- argparse types


def _int(text: str, what: str) -> int:
    try:
        return int(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from err


def nonnegative_int(text: str) -> int:
    """An integer >= 0 (argparse type)."""
    value = _int(text, "an integer >= 0")
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {value}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1 (argparse type)."""
    value = _int(text, "an integer >= 1")
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {value}")
    return value


def finite_float(text: str) -> float:
    """A finite number (argparse type)."""
    try:
        value = float(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from err
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """A finite number > 0 (argparse type)."""
    value = finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def nonnegative_float(text: str) -> float:
    """A finite number >= 0 (argparse type)."""
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def _radians(text: str) -> float:
    """Degrees at the command line -> radians for the library (argparse type)."""
    return math.radians(finite_float(text))


# ----------------------------------------------------------------------- shared options


class _Given(argparse.Action):
    """Store the value and remember that it was given (``<dest>_given``)."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        setattr(namespace, self.dest, values)
        setattr(namespace, self.dest + "_given", True)


def add_seed(
    parser: argparse._ActionsContainer, *, overrides: str = "", default: int = DEFAULT_SEED
) -> None:
    """``--seed N``: an integer >= 0, default ``default`` (0).

    ``overrides`` names another source of the seed (``"the --params file's seed"``) that is
    used unless ``--seed`` is given; ``args.seed_given`` tells which.
    """
    said = f"default {default}" if not overrides else f"default {overrides}"
    parser.add_argument(
        "--seed",
        type=nonnegative_int,
        default=default,
        action=_Given,
        metavar="N",
        help=f"random seed, an integer >= 0 ({said}; printed)",
    )
    parser.set_defaults(seed_given=False)


def default_out(command: str) -> Path:
    """The default output folder of ``command`` (words joined by ``-``): ``symloc-<command>``."""
    return Path("symloc-" + "-".join(command.split()))


def add_out(parser: argparse._ActionsContainer, command: str, *, what: str = "") -> None:
    """``--out DIR``: the folder the command writes into, default ``symloc-<command>``.

    ``command`` is the command's words after ``symloc`` (``"experiment table1"``); ``what``
    lists what goes there, for the help.
    """
    default = default_out(command)
    extra = f": {what}" if what else ""
    parser.add_argument(
        "--out",
        type=Path,
        default=default,
        metavar="DIR",
        help=f"output folder, created if needed (default {default}){extra}",
    )


def add_json(parser: argparse._ActionsContainer) -> None:
    """``--json PATH``: also write the results as standard JSON."""
    parser.add_argument(
        "--json",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write the results here as JSON (standard: null for missing values)",
    )


def add_lidar(parser: argparse._ActionsContainer, *, help: str = "simulated lidar") -> None:
    """``--lidar NAME``: one lidar preset, default ``rplidar_a2``."""
    parser.add_argument(
        "--lidar",
        choices=LIDARS,
        default=DEFAULT_LIDAR,
        metavar="NAME",
        help=f"{help}: {', '.join(LIDARS)} (default {DEFAULT_LIDAR}, the paper's)",
    )


def _lidar_list(text: str) -> str:
    if text != "all" and text not in LIDARS:
        raise argparse.ArgumentTypeError(
            f"expected one of {', '.join(LIDARS)} or all, got {text!r}"
        )
    return text


def add_lidars(parser: argparse._ActionsContainer, *, help: str = "simulated lidars") -> None:
    """``--lidar NAME [NAME ...]``: lidar presets to sweep, default ``rplidar_a2``; ``all``
    sweeps every preset. Read the value with :func:`lidar_names`."""
    parser.add_argument(
        "--lidar",
        nargs="+",
        type=_lidar_list,
        default=[DEFAULT_LIDAR],
        metavar="NAME",
        help=f"{help}: one or more of {', '.join(LIDARS)}, or all (default {DEFAULT_LIDAR})",
    )


def lidar_names(value: str | Sequence[str]) -> list[str]:
    """The preset names of a ``--lidar`` value (``all`` expanded, duplicates removed)."""
    names = [value] if isinstance(value, str) else list(value)
    out: list[str] = []
    for n in names:
        for m in LIDARS if n == "all" else (n,):
            if m not in out:
                out.append(m)
    return out


def add_room(
    parser: argparse._ActionsContainer,
    *,
    choices: Sequence[str] = ROOMS,
    help: str = "simulated room",
    default: str | None = DEFAULT_ROOM,
    default_help: str | None = None,
) -> None:
    """``--room NAME``: a simulated room, default ``default`` (``square``; None: the command
    decides, and ``default_help`` says what it does)."""
    parser.add_argument(
        "--room",
        choices=tuple(choices),
        default=default,
        metavar="NAME",
        help=f"{help}: {', '.join(choices)} (default {default_help or default})",
    )


def add_rooms(
    parser: argparse._ActionsContainer,
    *,
    rooms: Sequence[str],
    choices: Sequence[str] | None = None,
    help: str = "rooms to run",
) -> None:
    """``--rooms NAME [NAME ...]``: rooms a sweep runs, default ``all`` (the command's
    ``rooms``); read the value with :func:`room_names`."""
    allowed = tuple(choices if choices is not None else rooms)
    parser.add_argument(
        "--rooms",
        nargs="+",
        choices=(*allowed, "all"),
        default=["all"],
        metavar="NAME",
        help=f"{help}: one or more of {', '.join(allowed)}, or all (default all:"
        f" {', '.join(rooms)})",
    )


def room_names(value: Sequence[str], rooms: Sequence[str]) -> list[str]:
    """The room names of a ``--rooms`` value (``all`` is ``rooms``; duplicates removed)."""
    out: list[str] = []
    for n in value:
        for m in rooms if n == "all" else (n,):
            if m not in out:
                out.append(m)
    return out


def add_trials(parser: argparse._ActionsContainer, *, default: int, what: str = "trials") -> None:
    """``--trials N``: an integer >= 1; ``what`` says what is counted."""
    parser.add_argument(
        "--trials",
        type=positive_int,
        default=default,
        metavar="N",
        help=f"{what}, an integer >= 1 (default {default})",
    )


def add_angle(
    parser: argparse._ActionsContainer,
    flag: str,
    *,
    default: float | None,
    help: str,
    metavar: str = "DEG",
    dest: str | None = None,
) -> None:
    """An angle option: **degrees** at the command line, stored in **radians** for the library.

    ``default`` is in degrees (None: no default); ``dest`` names the attribute (give one
    without a ``_deg`` suffix for flags like ``--step-deg``: the value is in radians).
    """
    shown = "" if default is None else f", default {default:g} deg"
    parser.add_argument(
        flag,
        dest=dest or flag.lstrip("-").replace("-", "_"),
        type=_radians,
        default=None if default is None else math.radians(default),
        metavar=metavar,
        help=f"{help} [degrees{shown}]",
    )


# ----------------------------------------------------------------------- text for people


def direction_text(index: int, count: int | None = None) -> str:
    """A place's direction for people: 1-based (library index 0 is direction 1)."""
    return f"{int(index) + 1}" + ("" if count is None else f" of {int(count)}")


def order_text(order: SymmetryOrder | None) -> str:
    """A symmetry order for people: ``inf`` for a circle, ``-`` for none (an unknown verdict)."""
    return "-" if order is None else str(order)


# ----------------------------------------------------------------------- JSON


def json_safe(value: Any) -> Any:
    """``value`` as standard-JSON Python: non-finite floats become None, NumPy scalars and
    arrays plain numbers and lists, paths strings, tuples lists."""
    import numpy as np

    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, Mapping):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value


def write_json(path: Path, data: Mapping[str, Any]) -> Path:
    """Write ``data`` as standard JSON (no NaN: null) to ``path``, creating its folder."""
    from symloc.files.atomic import atomic_write_text

    text = json.dumps(json_safe(dict(data)), indent=2, sort_keys=True, allow_nan=False)
    return atomic_write_text(Path(path), text + "\n")


# ----------------------------------------------------------------------- inputs and outputs


def refuse_overwriting_inputs(
    inputs: Mapping[str, Path | None], outputs: Mapping[str, Path | None]
) -> None:
    """Nothing is written into a file the command was asked to read: raise
    :class:`~symloc.errors.ConfigurationError` when an output path is an input path (or, for an
    output folder, contains one among the files it will write)."""
    from symloc.errors import ConfigurationError

    ins = {name: Path(p).resolve() for name, p in inputs.items() if p is not None}
    for out_name, out in outputs.items():
        if out is None:
            continue
        o = Path(out).resolve()
        for in_name, i in ins.items():
            if o == i:
                raise ConfigurationError(
                    f"{out_name}: {out} is the {in_name} file this command reads; symloc never"
                    " writes into its input: choose another path"
                )
