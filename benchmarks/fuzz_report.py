"""Count the fuzz suite's inputs and escapes per target (``tests/fuzz``), without failing.

    python benchmarks/fuzz_report.py                       # the code on the path (this tree)
    PYTHONPATH=/path/to/older/src python benchmarks/fuzz_report.py   # e.g. before the fixes

Runs the same derandomized hypothesis inputs as ``tests/fuzz/test_fuzz.py`` (so the counts are
the CI's) with ``SYMLOC_FUZZ_COUNT_ONLY=1``: an input that lets a non-symloc exception escape,
hangs, or leaves the node unused 5 scans after a garbage burst is counted, not raised. Prints
one line per target: inputs, accepted, refused with a symloc error, escapes, and the most
frequent escape messages.
"""

from __future__ import annotations

import os
import sys
import tempfile
import warnings
from collections import Counter
from pathlib import Path

os.environ["SYMLOC_FUZZ_COUNT_ONLY"] = "1"
HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE.parent / "tests" / "fuzz"), str(HERE.parent / "tests")]

import fuzz_targets  # noqa: E402
import test_fuzz  # noqa: E402


class _Tmp:
    def __init__(self, root: Path) -> None:
        self.root = root

    def mktemp(self, name: str) -> Path:
        return Path(tempfile.mkdtemp(prefix=name, dir=self.root))


def main() -> int:
    import symloc

    print(f"# fuzz report: symloc from {Path(symloc.__file__).parent}")
    escapes: dict[str, Counter[str]] = {}
    original_guard = fuzz_targets.guard

    def guard(target: str, fn, *, allowed=(fuzz_targets.SymlocError,)):  # type: ignore[no-untyped-def]
        outcome = original_guard(target, fn, allowed=allowed)
        if outcome.startswith("escape"):
            escapes.setdefault(target, Counter())[outcome[:110]] += 1
        return outcome

    test_fuzz.guard = guard
    warnings.simplefilter("ignore")
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
        ]
        for name, run in runs:
            try:
                run()
            except Exception as err:  # a target that cannot even run on this code
                print(f"{name}: could not run ({type(err).__name__}: {err})")
    total = Counter()
    for target, c in sorted(fuzz_targets.counts.items()):
        n = sum(c.values())
        total.update(c)
        print(
            f"{target:<14} {n:>5} inputs: {c['ok']:>5} accepted, {c['refused']:>5} refused,"
            f" {c['escape']:>4} escapes"
        )
        for text, k in escapes.get(target, Counter()).most_common(4):
            print(f"{'':<16}{k:>4} x {text}")
    print(
        f"{'total':<14} {sum(total.values()):>5} inputs: {total['ok']:>5} accepted,"
        f" {total['refused']:>5} refused, {total['escape']:>4} escapes"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
