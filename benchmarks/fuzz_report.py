"""Count the fuzz suite's inputs and failures per target (``tests/fuzz``), without failing.

    PYTHONPATH=src python3 benchmarks/fuzz_report.py [--scale K] [--targets NAME ...]
    PYTHONPATH=/path/to/older/src python3 benchmarks/fuzz_report.py   # e.g. before the fixes

Runs the derandomized hypothesis inputs of ``tests/fuzz/test_fuzz.py`` (``--scale 1``: the
CI's inputs; ``--scale K``: K times as many per target, new ones included) with
``SYMLOC_FUZZ_COUNT_ONLY=1``: an input that lets a non-symloc exception escape (or prints a
traceback, or succeeds where it must fail), hangs, or allocates too much is counted, not
raised. The families: every file loader (map files, images, vocabularies, CARMEN logs, visual
maps, bags, node parameters), the node's message handlers (25 messages per sequence, each
counted), and the command line (garbage files and values, output paths of every command,
missing data sets, numeric bounds).

Bounds (issue 31): a hang is an input running over 60 s (``SYMLOC_FUZZ_TIME_BOUND``); an
allocation over 2 GB is caught two ways: the address space is limited to what the process
holds after its imports plus 2 GiB (an attempt to allocate more raises MemoryError, counted
as ``big``), and the peak resident memory of every input is measured (``/proc/self/status``
VmHWM, reset before each input through ``/proc/self/clear_refs``); over 2 GiB above the level
before the input counts as ``big`` too.

Prints one line per target: inputs, accepted, refused with a symloc error, tracebacks
(escapes), hangs, big allocations, and the most frequent escape messages; then the totals.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
import warnings
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

os.environ["SYMLOC_FUZZ_COUNT_ONLY"] = "1"
os.environ.setdefault("SYMLOC_FUZZ_TIME_BOUND", "60")
HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE.parent / "tests" / "fuzz"), str(HERE.parent / "tests")]

GIB = 1 << 30
#: Allocation that counts as unbounded (issue 31: "0 allocations over 2 GB").
BIG = 2 * GIB


class _Tmp:
    def __init__(self, root: Path) -> None:
        self.root = root

    def mktemp(self, name: str) -> Path:
        return Path(tempfile.mkdtemp(prefix=name, dir=self.root))


def _status_kib(key: str) -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1])
    return 0


def _reset_peak() -> bool:
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        return False
    return True


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scale", type=float, default=1.0, help="inputs per target x K (default 1)")
    ap.add_argument("--targets", nargs="*", default=None, help="only these targets")
    args = ap.parse_args(argv)
    os.environ["SYMLOC_FUZZ_SCALE"] = str(args.scale)

    import fuzz_targets
    import test_fuzz

    import symloc
    from symloc.cli.main import build_parser

    build_parser()  # import every command (and their libraries) before the limit is set
    import cv2  # noqa: F401
    import gtsam  # noqa: F401
    import rosbags.rosbag2  # noqa: F401

    vm = _status_kib("VmSize") * 1024
    limit = vm + BIG
    resource.setrlimit(resource.RLIMIT_AS, (limit, resource.RLIM_INFINITY))
    can_reset = _reset_peak()
    print(f"# fuzz report: symloc from {Path(symloc.__file__).parent}")
    print(
        f"# scale {args.scale:g}; hang bound {fuzz_targets.TIME_BOUND:g} s; address space"
        f" {vm / GIB:.2f} GiB after imports + 2 GiB; per-input peak RSS"
        f" {'measured' if can_reset else 'NOT measured (no /proc/self/clear_refs)'}"
    )
    escapes: dict[str, Counter[str]] = {}
    kinds: dict[str, Counter[str]] = {}
    examples: dict[str, list[str]] = {}
    original_guard = fuzz_targets.guard

    def guard(
        target: str, fn: Callable[[], Any], *, allowed: Any = (fuzz_targets.SymlocError,)
    ) -> str:
        before = _status_kib("VmRSS")
        _reset_peak()
        outcome = original_guard(target, fn, allowed=allowed)
        grew = (_status_kib("VmHWM") - before) * 1024
        k = kinds.setdefault(target, Counter())
        if outcome.startswith("escape: Hang"):
            k["hang"] += 1
        elif outcome.startswith("escape: MemoryError") or grew > BIG:
            k["big"] += 1
        elif outcome.startswith("escape"):
            k["traceback"] += 1
        if outcome.startswith("escape"):
            escapes.setdefault(target, Counter())[outcome[:110]] += 1
            if fuzz_targets.last_argv[0]:
                examples.setdefault(outcome[:110], fuzz_targets.last_argv[0])
            fuzz_targets.last_argv[0] = []
        return outcome

    # the detector itself: an input that allocates 3 GiB must count as "over 2 GB"
    import numpy as np

    guard("self check", lambda: np.ones(3 * GIB, np.uint8))
    caught = kinds.pop("self check", Counter())["big"] == 1
    fuzz_targets.counts.pop("self check", None)
    escapes.pop("self check", None)
    examples.clear()
    print(f"# self check: an input allocating 3 GiB is counted over 2 GB: {caught}")
    test_fuzz.guard = guard
    warnings.simplefilter("ignore")
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory() as root:
        tmp = _Tmp(Path(root))
        runs = [
            ("map files", lambda: test_fuzz.test_map_files(tmp)),
            ("images", lambda: test_fuzz.test_images(tmp)),
            ("vocabularies", lambda: test_fuzz.test_vocabularies(tmp)),
            ("carmen logs", lambda: test_fuzz.test_carmen_logs(tmp)),
            ("visual maps", lambda: test_fuzz.test_visual_maps(tmp)),
            (
                "bags",
                lambda: test_fuzz.test_bags(tmp, test_fuzz.build_small_bags(tmp.mktemp("b"))),
            ),
            ("node params", test_fuzz.test_node_params),
            ("node messages", test_fuzz.test_node_messages_never_escape_and_the_node_recovers),
            ("commands", lambda: test_fuzz.test_commands(tmp)),
            ("output paths", lambda: test_fuzz.test_output_paths(tmp)),
            ("missing data", lambda: test_fuzz.test_missing_data(tmp)),
            ("numeric bounds", test_fuzz.test_numeric_bounds),
            ("special files", lambda: test_fuzz.test_special_files(tmp)),
        ]
        cwd = os.getcwd()
        os.chdir(root)  # commands that fall back to their default --out write here
        try:
            for name, run in runs:
                if args.targets and name not in args.targets:
                    continue
                t0 = time.perf_counter()
                try:
                    run()
                except Exception as err:  # a target that cannot even run on this code
                    print(f"{name}: could not run ({type(err).__name__}: {str(err)[:200]})")
                print(f"#   {name}: {time.perf_counter() - t0:.0f} s", flush=True)
        finally:
            os.chdir(cwd)
    total: Counter[str] = Counter()
    bad: Counter[str] = Counter()
    for target, c in sorted(fuzz_targets.counts.items()):
        n = sum(c.values())
        total.update(c)
        k = kinds.get(target, Counter())
        bad.update(k)
        print(
            f"{target:<15} {n:>6} inputs: {c['ok']:>6} ok, {c['refused']:>6} refused,"
            f" {k['traceback']:>4} tracebacks, {k['hang']:>3} hangs, {k['big']:>3} over 2 GB"
        )
        for text, m in escapes.get(target, Counter()).most_common(4):
            print(f"{'':<17}{m:>4} x {text}")
            if text in examples:
                print(f"{'':<24}e.g. symloc {' '.join(map(repr, examples[text]))}")
    print(
        f"{'total':<15} {sum(total.values()):>6} inputs: {total['ok']:>6} ok,"
        f" {total['refused']:>6} refused, {bad['traceback']:>4} tracebacks, {bad['hang']:>3}"
        f" hangs, {bad['big']:>3} over 2 GB  ({time.perf_counter() - t_start:.0f} s)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
