"""``symloc experiment symmetry-carmen``: the symmetry judgement on every scan of real logs.

The CARMEN logs in the shared data (Intel lab, ACES building, Freiburg 079) carry 180-degree
front scans (SICK LMS), so no scan shows a whole room. Each scan is judged twice:

- ``strict``: the default judgement (:class:`SymmetryConfig` defaults), which needs a
  360-degree scan for any claim and must answer "unknown" here;
- ``partial``: ``SymmetryConfig(partial_view=True)``, which tests a partial view for the one
  symmetric pattern it can show, a hallway (two long parallel walls on either side, far ends
  beyond range), assuming the unseen part behind the sensor continues it.

Printed per log: the count of each verdict kind for both, the count of scans judged
symmetric, and the reasons grouped by the test that decided. Figures: the scans judged
symmetric (up to ``--examples`` per log, spread over the log) with their fitted lines, centre
and axis, so a person can check whether they are real corridors or false positives; a seeded
random sample of the scans that look like corridors (:func:`corridor_like`, a diagnostic: the
two longest walls parallel, one on each side) with the verdict on each; and a seeded random
sample of the other verdicts, to check that the judgement does not miss obvious symmetric
places.

The range noise is the SICK LMS data-sheet figure (``--range-sigma``, default 0.01 m: the
logs are in centimetre mode); nothing is tuned to the logs.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from symloc._checks import as_rng
from symloc.bench.shared_data import CARMEN_LOGS, carmen_log_paths, find_carmen_dir
from symloc.cli import options
from symloc.errors import ConfigurationError
from symloc.experiments._common import (
    add_common_arguments,
    print_config,
    write_json,
    write_results_file,
)

__all__ = [
    "CARMEN_LOGS",
    "corridor_like",
    "find_carmen_dir",
    "reason_tag",
    "register",
    "run_symmetry_carmen",
]


#: Reason tags by the phrase that starts (or marks) the judgement's reason.
_TAGS = (
    ("too few points", "too few points"),
    ("field of view", "field of view < 360 deg"),
    ("partial view", "partial view: not a hallway"),
    ("hallway", "hallway"),
    ("an opening", "opening in a straight wall (door)"),
    ("the contour is open", "contour open (walls beyond range)"),
    ("the walls do not close", "walls do not close (occlusion)"),
    ("clutter", "clutter off the walls"),
    ("no rotation", "corners not rotationally symmetric"),
    ("circle", "circle test"),
    ("failed on this scan", "judgement failed"),
)


def reason_tag(reason: str) -> str:
    """A short name of the test that decided a verdict, from its reason text."""
    low = reason.lower()
    for key, tag in _TAGS:
        if key in low:
            return tag
    return "other"


def corridor_like(lines: Any, *, min_length: float = 2.0, max_angle_deg: float = 3.0) -> bool:
    """Whether the two longest walls of a scan look like a corridor around the sensor.

    A diagnostic, not a judgement: the two longest lines (of at least 3 points and
    ``min_length`` [m]) are parallel within ``max_angle_deg`` and on either side of the sensor.
    Used to find the scans a person would call "in a corridor" and show what the judgement
    says about them.
    """
    ok = (lines.n_points >= 3) & (
        np.hypot(*(lines.segments[:, 1] - lines.segments[:, 0]).T) >= min_length
    )
    if int(ok.sum()) < 2:
        return False
    seg = lines.segments[ok]
    length = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
    i, j = np.argsort(length)[-2:]
    d = seg[[i, j], 1] - seg[[i, j], 0]
    d /= np.hypot(d[:, 0], d[:, 1])[:, None]
    if abs(float(d[0, 0] * d[1, 0] + d[0, 1] * d[1, 1])) < np.cos(np.radians(max_angle_deg)):
        return False
    nrm = np.array([-d[0, 1], d[0, 0]])
    return bool(float(seg[i, 0] @ nrm) * float(seg[j, 0] @ nrm) < 0)


def run_symmetry_carmen(
    data_dir: Path,
    logs: tuple[str, ...] | list[str] = CARMEN_LOGS,
    *,
    range_sigma: float = 0.01,
    stride: int = 1,
    progress: bool = True,
) -> dict[str, Any]:
    """Judge every ``stride``-th scan of each log, strictly and with ``partial_view``.

    Parameters
    ----------
    data_dir : Path
        Folder with ``<log>-corrected.log.gz``.
    logs : sequence of str
        Log names (``intel``, ``aces``, ``freiburg-079``).
    range_sigma : float
        Range noise [m] the tolerances follow from (> 0).
    stride : int
        Judge scans 0, stride, 2 stride, ... (>= 1).
    progress : bool
        Show a tqdm bar on stderr.

    Returns
    -------
    dict
        ``{"logs": {name: {"path", "n_scans", "n_judged", "strict": {kind: count},
        "partial": {kind: count}, "strict_symmetric", "partial_symmetric",
        "partial_reasons": {tag: count}, "symmetric_indices": [...], "kind_indices":
        {kind: [...]}, "corridor_like", "corridor_indices", "corridor_verdicts", "ms_strict",
        "ms_partial"}}}``; indices are scan indices in the log.

    Raises
    ------
    ConfigurationError
        For a bad stride, noise, or unknown log name.
    DataFormatError
        When a log file is missing or malformed.
    """
    from symloc.io.carmen import read_carmen
    from symloc.symmetry import SymmetryConfig, judge_symmetry, scan_lines

    if isinstance(stride, bool) or not isinstance(stride, int) or stride < 1:
        raise ConfigurationError(f"stride: expected an integer >= 1, got {stride!r}")
    for name in logs:
        if name not in CARMEN_LOGS:
            raise ConfigurationError(f"logs: expected names from {CARMEN_LOGS}, got {name!r}")
    strict_cfg = SymmetryConfig(range_sigma=range_sigma)
    partial_cfg = SymmetryConfig(range_sigma=range_sigma, partial_view=True)
    out: dict[str, Any] = {"logs": {}}
    for name in logs:
        path = Path(data_dir) / f"{name}-corrected.log.gz"
        log = read_carmen(path)
        picked = range(0, len(log.scans), stride)
        strict: Counter[str] = Counter()
        partial: Counter[str] = Counter()
        reasons: Counter[str] = Counter()
        kind_idx: dict[str, list[int]] = {}
        sym_idx: list[int] = []
        corridor_idx: list[int] = []
        corridor_kinds: Counter[str] = Counter()
        n_strict_sym = 0
        cpu_strict = cpu_partial = 0.0
        for i in tqdm(picked, desc=name, disable=not progress, file=sys.stderr, leave=False):
            scan = log.scans[i].scan
            c0 = time.process_time()
            r_s = judge_symmetry(scan, config=strict_cfg)
            c1 = time.process_time()
            r_p = judge_symmetry(scan, config=partial_cfg)
            cpu_partial += time.process_time() - c1
            cpu_strict += c1 - c0
            strict[r_s.kind] += 1
            n_strict_sym += int(r_s.symmetric)
            partial[r_p.kind] += 1
            reasons[f"{r_p.kind}: {reason_tag(r_p.reason)}"] += 1
            kind_idx.setdefault(r_p.kind, []).append(i)
            if r_p.symmetric:
                sym_idx.append(i)
            if corridor_like(scan_lines(scan, partial_cfg)):
                corridor_idx.append(i)
                corridor_kinds[f"{r_p.kind}: {reason_tag(r_p.reason)}"] += 1
        n = len(picked)
        out["logs"][name] = {
            "path": str(path),
            "n_scans": len(log.scans),
            "n_judged": n,
            "beams": len(log.scans[0].scan) if log.scans else 0,
            "strict": dict(strict),
            "partial": dict(partial),
            "strict_symmetric": n_strict_sym,
            "partial_symmetric": len(sym_idx),
            "partial_reasons": dict(reasons.most_common()),
            "symmetric_indices": sym_idx,
            "kind_indices": kind_idx,
            "corridor_like": len(corridor_idx),
            "corridor_indices": corridor_idx,
            "corridor_verdicts": dict(corridor_kinds.most_common()),
            "ms_strict": 1e3 * cpu_strict / max(n, 1),
            "ms_partial": 1e3 * cpu_partial / max(n, 1),
        }
    return out


def _spread(indices: list[int], k: int) -> list[int]:
    """Up to k indices spread evenly over the list."""
    if len(indices) <= k:
        return list(indices)
    pos = np.linspace(0, len(indices) - 1, k).round().astype(int)
    return [indices[p] for p in pos]


def _figures(
    data_dir: Path, result: dict[str, Any], out: Path, examples: int, rng: np.random.Generator
) -> list[Path]:
    from symloc.figures.symmetry import plot_judgement_grid
    from symloc.io.carmen import read_carmen
    from symloc.symmetry import SymmetryConfig, judge_symmetry, scan_lines

    sym_items: list[tuple[Any, Any, Any, str]] = []
    other_items: list[tuple[Any, Any, Any, str]] = []
    for name, res in result["logs"].items():
        log = read_carmen(res["path"])
        cfg = SymmetryConfig(partial_view=True)
        for i in _spread(res["symmetric_indices"], examples):
            scan = log.scans[i].scan
            rep = judge_symmetry(scan, config=cfg)
            sym_items.append((scan, rep, scan_lines(scan, cfg), f"{name} scan {i}"))
        for kind in ("asymmetric", "unknown"):
            idx = res["kind_indices"].get(kind, [])
            if not idx:
                continue
            pick = sorted(rng.choice(idx, size=min(2, len(idx)), replace=False).tolist())
            for i in pick:
                scan = log.scans[i].scan
                rep = judge_symmetry(scan, config=cfg)
                other_items.append(
                    (scan, rep, scan_lines(scan, cfg), f"{name} scan {i}: {reason_tag(rep.reason)}")
                )
    corridor_items: list[tuple[Any, Any, Any, str]] = []
    for name, res in result["logs"].items():
        idx = res["corridor_indices"]
        if not idx:
            continue
        log = read_carmen(res["path"])
        cfg = SymmetryConfig(partial_view=True)
        pick = sorted(rng.choice(idx, size=min(4, len(idx)), replace=False).tolist())
        for i in pick:
            scan = log.scans[i].scan
            rep = judge_symmetry(scan, config=cfg)
            corridor_items.append(
                (scan, rep, scan_lines(scan, cfg), f"{name} scan {i}: {reason_tag(rep.reason)}")
            )
    n_sym = sum(r["partial_symmetric"] for r in result["logs"].values())
    n_cor = sum(r["corridor_like"] for r in result["logs"].values())
    return [
        plot_judgement_grid(
            corridor_items,
            out / "symmetry_carmen_corridors.png",
            title=f"CARMEN: corridor-like views ({n_cor} scans: two longest walls parallel, one"
            " on each side) and the judgement's verdict (partial_view=True), random sample",
        ),
        plot_judgement_grid(
            sym_items,
            out / "symmetry_carmen_symmetric.png",
            title=f"CARMEN scans judged symmetric (partial_view=True): {n_sym} in all,"
            f" up to {examples} per log shown",
        ),
        plot_judgement_grid(
            other_items,
            out / "symmetry_carmen_sample.png",
            title="CARMEN: random sample of scans judged not symmetric (partial_view=True)",
        ),
    ]


def _run(args: argparse.Namespace) -> int:
    data = next(iter(carmen_log_paths(args.logs, args.data).values())).parent
    if args.stride < 1 or args.examples < 0 or not (args.range_sigma > 0):
        raise ConfigurationError("--stride must be >= 1, --examples >= 0, --range-sigma > 0")
    config = {
        "seed": args.seed,
        "data": str(data),
        "logs": " ".join(args.logs),
        "stride": args.stride,
        "range_sigma [m]": args.range_sigma,
        "k_sigma": 5.0,
        "examples per log": args.examples,
    }
    print_config("symmetry-carmen", config)
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    result = run_symmetry_carmen(
        Path(data), args.logs, range_sigma=args.range_sigma, stride=args.stride
    )
    kinds = ("polygon", "circle", "rectangle", "hallway", "asymmetric", "unknown")
    head = " ".join(f"{k:>10}" for k in kinds)
    print(f"\n{'log':<13} {'mode':<8} {'judged':>7} {head} {'symmetric':>10}")
    for name, res in result["logs"].items():
        for mode in ("strict", "partial"):
            cnt = " ".join(f"{res[mode].get(k, 0):>10}" for k in kinds)
            print(f"{name:<13} {mode:<8} {res['n_judged']:>7} {cnt} {res[mode + '_symmetric']:>10}")
    print("\nreasons (partial_view=True):")
    for name, res in result["logs"].items():
        print(
            f"  {name} ({res['beams']} beams; CPU per judgement {res['ms_strict']:.2f} ms strict,"
            f" {res['ms_partial']:.2f} ms partial_view):"
        )
        for tag, c in res["partial_reasons"].items():
            print(f"    {c:>6}  {tag}")
        print(
            f"    corridor-like views (diagnostic, two longest walls parallel on either side):"
            f" {res['corridor_like']}, judged: {res['corridor_verdicts']}"
        )
        if res["symmetric_indices"]:
            shown = res["symmetric_indices"][:20]
            print(f"    symmetric scans (first {len(shown)}): {shown}")
    total = sum(r["n_judged"] for r in result["logs"].values())
    n_sym = sum(r["partial_symmetric"] for r in result["logs"].values())
    n_strict = sum(r["strict_symmetric"] for r in result["logs"].values())
    print(
        f"\n{total} scans judged: {n_strict} symmetric (strict, 360 deg needed),"
        f" {n_sym} symmetric with partial_view=True"
    )
    summary = {
        "seed": args.seed,
        "range_sigma": args.range_sigma,
        "stride": args.stride,
        "symmetric_strict": n_strict,
        "symmetric_partial": n_sym,
        "n_judged": total,
        **result,
    }
    write_results_file(
        args,
        clock,
        config,
        {
            "symmetric_strict": n_strict,
            "symmetric_partial": n_sym,
            "n_judged": total,
            "logs": {
                name: {k: v for k, v in res.items() if not k.endswith("_indices") and k != "path"}
                for name, res in result["logs"].items()
            },
        },
    )
    if not args.no_figure:
        rng = as_rng(args.seed)
        args.out.mkdir(parents=True, exist_ok=True)
        for p in _figures(Path(data), result, args.out, args.examples, rng):
            print(f"wrote {p}")
    write_json(args.json, summary)
    return 0


def register(subparsers: Any) -> None:
    """Add ``symloc experiment symmetry-carmen``."""
    parser = subparsers.add_parser(
        "symmetry-carmen",
        help="symmetry judgement on every scan of the real CARMEN logs (180-degree scans)",
    )
    add_common_arguments(parser, "symmetry-carmen")
    parser.add_argument(
        "--data", type=Path, default=None, metavar="DIR", help="folder of the CARMEN logs"
    )
    parser.add_argument(
        "--logs", nargs="+", choices=CARMEN_LOGS, default=list(CARMEN_LOGS), help="logs to judge"
    )
    parser.add_argument(
        "--stride", type=options.positive_int, default=1, help="judge every N-th scan (default 1)"
    )
    parser.add_argument(
        "--range-sigma",
        type=options.positive_float,
        default=0.01,
        help="range noise [m] the tolerances follow from (default 0.01, SICK LMS cm mode)",
    )
    parser.add_argument(
        "--examples",
        type=options.count,
        default=6,
        help="symmetric scans per log in the figure",
    )
    parser.add_argument("--no-figure", action="store_true", help="skip the PNG figures")
    options.add_results(parser, "docs/results/symmetry_carmen.json")
    parser.set_defaults(func=_run)
