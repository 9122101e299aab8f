"""Benchmark: the world generator over many seeds, per family.

For every family of :data:`symloc.sim.generator.FAMILIES` and seeds 0 .. N-1 (``perturb=None``:
the seed decides, about half are perturbed), generate the world, build it and record the computed
symmetry order and the time to generate (generation includes the validity checks; building is
timed separately). Prints a Markdown table: the share of worlds with each order (bare and
perturbed apart) and the median / 95th-percentile times.

Run: ``python benchmarks/bench_worlds.py [--seeds 500] [--families regular circle ...]``
"""

from __future__ import annotations

import argparse
import collections
import os
import time

import numpy as np

from symloc.sim.generator import FAMILIES, generate_world


def _orders(counts: collections.Counter[int], total: int) -> str:
    if total == 0:
        return "-"
    parts = [f"{k}: {100 * v / total:.0f}%" for k, v in sorted(counts.items())]
    return ", ".join(parts)


def main() -> None:
    """Run the benchmark and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=500)
    ap.add_argument("--families", nargs="*", default=list(FAMILIES))
    args = ap.parse_args()
    print(f"# bench_worlds seeds=0..{args.seeds - 1} perturb=None load={os.getloadavg()[0]:.2f}")
    print(
        "| family | parameters | worlds | bare: order share | perturbed: order share"
        " | generate median / p95 [ms] | build median [ms] |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name in args.families:
        fam = FAMILIES[name]
        bare: collections.Counter[int] = collections.Counter()
        pert: collections.Counter[int] = collections.Counter()
        gen_t: list[float] = []
        build_t: list[float] = []
        for seed in range(args.seeds):
            t0 = time.perf_counter()
            spec = generate_world(name, seed)
            t1 = time.perf_counter()
            room = spec.build()
            t2 = time.perf_counter()
            gen_t.append(t1 - t0)
            build_t.append(t2 - t1)
            (pert if "perturbed:" in spec.description else bare)[room.order] += 1
        params = ", ".join(f"{k} {lo:g}-{hi:g}" for k, (lo, hi) in fam.params.items())
        g = 1000 * np.array(gen_t)
        print(
            f"| {name} | {params} | {args.seeds} | {_orders(bare, sum(bare.values()))}"
            f" (n={sum(bare.values())}) | {_orders(pert, sum(pert.values()))}"
            f" (n={sum(pert.values())}) | {np.median(g):.0f} / {np.percentile(g, 95):.0f}"
            f" | {1000 * np.median(build_t):.0f} |",
            flush=True,
        )
    print(f"# load at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
