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
                (a file: never an existing folder)
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
:func:`positive_int`, :func:`positive_float`, :func:`finite_float`, and :func:`bounded` for an
upper bound): a bad value is a usage error naming the option, exit code 2, never a traceback.

Every path a command writes is declared with :func:`output_folder` or :func:`output_file` as
its type (``--out``, ``--json``, ``--png``, ``--build-map``, ...): the path is checked while the
arguments are parsed, so an existing file where a folder is expected, a folder where a file is
expected, a special file, or a parent that is a file or cannot be written is a usage error
naming the option and the path (exit code 2) before any work starts. The default ``--out``
folder is checked as well (argparse converts string defaults).

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
import os
import stat
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from symloc.lidar_spec import PRESETS
from symloc.mcl.params import MAX_PARTICLES, PARTICLE_MEMORY

if TYPE_CHECKING:  # a type only: symloc.symmetry loads the features' numba kernels
    from symloc.symmetry.order import SymmetryOrder

__all__ = [
    "DEFAULT_LIDAR",
    "DEFAULT_ROOM",
    "DEFAULT_SEED",
    "ROOMS",
    "Bounded",
    "add_angle",
    "add_json",
    "add_lidar",
    "add_lidars",
    "add_out",
    "add_room",
    "add_rooms",
    "add_seed",
    "add_trials",
    "bounded",
    "default_out",
    "direction_text",
    "file_stem",
    "finite_float",
    "integer",
    "json_safe",
    "lidar_names",
    "nonnegative_int",
    "order_text",
    "output_file",
    "output_folder",
    "output_problem",
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


def integer(text: str) -> int:
    """Any integer (argparse type)."""
    return _int(text, "an integer")


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


class Bounded:
    """An argparse type: ``kind`` (e.g. :func:`positive_int`) within ``[low, high]``.

    ``why`` says where the bound comes from (memory, time), and is part of the error, e.g.
    ``expected at most 4,000,000 (about 240 B per particle in an update: 4 M particles need
    about 1 GB), got 1000000000``. ``unit`` follows the numbers in the message. ``low``,
    ``high`` and ``kind`` stay readable (the fuzz suite draws values beyond them).
    """

    def __init__(
        self,
        kind: Callable[[str], float],
        *,
        low: float | None = None,
        high: float | None = None,
        why: str,
        unit: str = "",
    ) -> None:
        self.kind = kind
        self.low = low
        self.high = high
        self.why = why
        self.unit = unit
        self.__name__ = f"bounded_{getattr(kind, '__name__', 'value')}"

    @staticmethod
    def _shown(bound: float) -> str:
        return f"{int(bound):,}" if float(bound).is_integer() else f"{bound:g}"

    def __call__(self, text: str) -> Any:
        value = self.kind(text)
        u = f" {self.unit}" if self.unit else ""
        if self.high is not None and value > self.high:
            raise argparse.ArgumentTypeError(
                f"expected at most {self._shown(self.high)}{u} ({self.why}), got {text}"
            )
        if self.low is not None and value < self.low:
            raise argparse.ArgumentTypeError(
                f"expected at least {self._shown(self.low)}{u} ({self.why}), got {text}"
            )
        return value


def bounded(
    kind: Callable[[str], float],
    *,
    low: float | None = None,
    high: float | None = None,
    why: str,
    unit: str = "",
) -> Bounded:
    """``kind`` within ``[low, high]`` as an argparse type (:class:`Bounded`)."""
    return Bounded(kind, low=low, high=high, why=why, unit=unit)


#: Longest name of one path component (bytes; Linux NAME_MAX).
NAME_MAX = 255

_SPECIAL = {
    stat.S_IFIFO: "a FIFO",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
}


def _kind_of(mode: int) -> str:
    return _SPECIAL.get(stat.S_IFMT(mode), "not a regular file")


def _writable(folder: Path) -> bool:
    return os.access(folder, os.W_OK | os.X_OK)


def output_problem(path: Path | str, *, folder: bool) -> str | None:
    """Why ``path`` cannot be written as an output, or None if it can.

    ``folder``: the output is a folder the command creates (if missing) and writes files into;
    otherwise it is one file, written by replacing it atomically (so its folder must be
    writable). A missing path is fine when its nearest existing ancestor is a folder this user
    can write into (missing folders are created). The file system is only inspected.
    """
    text = os.fspath(path)
    if not text:
        return "is an empty path; expected " + ("a folder" if folder else "a file name")
    if "\x00" in text:
        return "contains a NUL character"
    p = Path(text)
    for part in p.parts:
        if len(os.fsencode(part)) > NAME_MAX:
            return f"has a name ({part[:24]!r}...) longer than {NAME_MAX} bytes"
    if not folder and (text.endswith(os.sep) or p.name in ("", ".", "..")):
        return "names a folder; expected a file name"
    try:
        st = p.stat()
    except (FileNotFoundError, NotADirectoryError):
        st = None
    except OSError as err:
        return f"cannot be inspected ({err.strerror})"
    if st is not None:
        if folder:
            if not stat.S_ISDIR(st.st_mode):
                kind = "an existing file" if stat.S_ISREG(st.st_mode) else _kind_of(st.st_mode)
                return f"is {kind}; expected a folder (created if missing)"
            if not _writable(p):
                return "is a folder this user cannot write into"
            return None
        if stat.S_ISDIR(st.st_mode):
            return "is an existing folder; expected a file name"
        if not stat.S_ISREG(st.st_mode):
            return f"is {_kind_of(st.st_mode)}; expected a regular file (or a new name)"
        if not _writable(p.parent):
            return f"cannot be replaced: its folder {p.parent} is not writable"
        return None
    ancestor = p.parent
    while True:
        try:
            st = ancestor.stat()
            break
        except (FileNotFoundError, NotADirectoryError):
            if ancestor == ancestor.parent:
                return "has no existing ancestor folder"
            ancestor = ancestor.parent
        except OSError as err:
            return f"cannot be inspected at {ancestor} ({err.strerror})"
    if not stat.S_ISDIR(st.st_mode):
        return f"cannot be created: {ancestor} is a file, not a folder"
    if not _writable(ancestor):
        return f"cannot be created: the folder {ancestor} is not writable"
    return None


def output_folder(text: str) -> Path:
    """An output folder (argparse type): created if missing, never an existing file; see
    :func:`output_problem`."""
    problem = output_problem(text, folder=True)
    if problem is not None:
        raise argparse.ArgumentTypeError(f"{text or repr(text)} {problem}")
    return Path(text)


def output_file(text: str) -> Path:
    """An output file (argparse type): a new name or a regular file to replace, never a
    folder or a special file, in a folder that can be written or created; see
    :func:`output_problem`."""
    problem = output_problem(text, folder=False)
    if problem is not None:
        raise argparse.ArgumentTypeError(f"{text or repr(text)} {problem}")
    return Path(text)


def file_stem(text: str) -> str:
    """A plain file name without folders (argparse type): ``--name`` of a written file."""
    if not text or text in (".", "..") or "/" in text or "\x00" in text:
        raise argparse.ArgumentTypeError(
            f"expected a plain file name (no '/', not empty, not . or ..), got {text!r}"
        )
    if len(os.fsencode(text)) > NAME_MAX - 32:  # room for suffixes and temporary names
        raise argparse.ArgumentTypeError(
            f"expected a name of at most {NAME_MAX - 32} bytes, got {len(os.fsencode(text))}"
        )
    return text


# Upper bounds of numeric options, each with where it comes from (said in the error).

#: Items of a counted option (trials, worlds, positions, photos, starts, ...).
MAX_COUNT = 10_000
COUNT_MEMORY = "each keeps its record, up to about 100 KB with its trajectory, in memory until the summary: 10,000 hold about 1 GB"
#: Largest G-V distance (centre to vertex) of a simulated room [m].
MAX_GV = 100.0
GV_MEMORY = (
    "the room and its lab are rasterised at 5 cm: 100 m is about 4,000 x 4,000 cells per grid;"
    " 3,000 m took 0.7 GB and 75 s"
)
#: Longest simulated run [s].
MAX_SIM_SECONDS = 3600.0
SIM_MEMORY = "the run keeps every scan and pose at 10 Hz: one simulated hour is 36,000 scans"
#: Most worker processes.
MAX_WORKERS = 64
WORKER_MEMORY = "each worker is a process of about 300 MB"
#: Most furniture items in a simulated room (as world files).
MAX_ITEMS = 200
ITEM_MEMORY = "as in world files: every item is raycast for every beam"


def _radians(text: str) -> float:
    """Degrees at the command line -> radians for the library (argparse type)."""
    return math.radians(finite_float(text))


#: A count of items (argparse type): an integer in [1, :data:`MAX_COUNT`].
count = bounded(positive_int, high=MAX_COUNT, why=COUNT_MEMORY)
#: Particles of a filter (argparse type): an integer in [1, 4,000,000].
particles = bounded(positive_int, high=MAX_PARTICLES, why=PARTICLE_MEMORY)
#: A simulated room's G-V distance [m] (argparse type): (0, 100].
gv_distance = bounded(positive_float, high=MAX_GV, why=GV_MEMORY, unit="m")
#: Simulated seconds (argparse type): (0, 3600].
sim_seconds = bounded(positive_float, high=MAX_SIM_SECONDS, why=SIM_MEMORY, unit="s")
#: Worker processes (argparse type): [1, 64].
workers = bounded(positive_int, high=MAX_WORKERS, why=WORKER_MEMORY)
#: Furniture items (argparse type): [0, 200].
items = bounded(nonnegative_int, high=MAX_ITEMS, why=ITEM_MEMORY)
#: A simulated room's side [m] (argparse type): (0, 100].
room_side = bounded(positive_float, high=MAX_GV, why=GV_MEMORY, unit="m")
#: Directions (images) of a place (argparse type): [1, 360].
directions = bounded(
    positive_int, high=360, why="one rendered image of about 1 MB and its features per direction"
)
#: Symmetry order of a place (argparse type): [1, 256] (the simulator's largest order).
symmetry_order = bounded(positive_int, high=256, why="the largest order symloc judges")
#: A camera's horizontal field of view [deg] (argparse type): (0, 179].
field_of_view = bounded(positive_float, high=179.0, why="a pinhole camera sees less than 180 deg")
#: A mapping trip's reach [m] (argparse type): [0, 100]; below :data:`MIN_MAPPING_REACH` only 0.
mapping_reach = bounded(
    nonnegative_float,
    high=MAX_GV,
    why="a stop is left where the trip passed farther than this from a reachable place",
    unit="m",
)
#: Shortest non-zero mapping reach [m]: a stop for every 0.2 m^2 of floor at most.
MIN_MAPPING_REACH = 0.25
#: Loops of a simulated mapping run (argparse type): (0, 100].
laps = bounded(
    positive_float,
    high=100.0,
    why="SLAM keeps every scan of the run: 100 laps of a room are about 100,000 scans",
)
#: Map cell size [m] (argparse type): [0.01, 1].
map_resolution = bounded(
    positive_float,
    low=0.01,
    high=1.0,
    why="1 cm cells put 10^8 cells in a 100 m map, over 1 GB in SLAM's grids; cells over 1 m"
    " hold no room",
    unit="m",
)
#: Worlds in one gallery figure (argparse type): [1, 256].
gallery_count = bounded(
    positive_int, high=256, why="every world is a panel of one figure held in memory"
)
#: Branching factor of a vocabulary (argparse type): [2, 256].
vocabulary_k = bounded(
    positive_int,
    low=2,
    high=256,
    why="k-means++ keeps a distance per descriptor per seed at every node",
)
#: Depth levels of a vocabulary (argparse type): [1, 10] (DBoW2's).
vocabulary_levels = bounded(positive_int, high=10, why="DBoW2's deepest tree")
#: ORB features per training image (argparse type): [1, 100,000].
orb_features = bounded(
    positive_int,
    high=100_000,
    why="every image's 32-byte descriptors are clustered together: 100,000 per image",
)


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
        type=output_folder,
        default=str(default),  # a string, so that argparse checks it with the type
        metavar="DIR",
        help=f"output folder, created if needed (default {default}){extra}",
    )


def add_json(parser: argparse._ActionsContainer) -> None:
    """``--json PATH``: also write the results as standard JSON."""
    parser.add_argument(
        "--json",
        type=output_file,
        default=None,
        metavar="PATH",
        help="also write the results here as JSON (standard: null for missing values)",
    )


def add_results(parser: argparse._ActionsContainer, example: str, *, note: str = "") -> None:
    """``--results PATH``: also write the run's results file (:mod:`symloc.bench.results_file`:
    its figures with the command, commit, date, machine and load); ``example`` is where the
    README's lives (``docs/results/NAME.json``), ``note`` anything more for the help."""
    parser.add_argument(
        "--results",
        type=output_file,
        default=None,
        metavar="PATH",
        help=f"also write the run's results file here (the README's: {example}){note}: the "
        "figures with the command, commit, date, machine and load; python -m symloc.readme "
        "re-renders the README from it",
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
        type=count,
        default=default,
        metavar="N",
        help=f"{what}, an integer in [1, {MAX_COUNT}] (default {default})",
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
