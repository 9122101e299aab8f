"""Benchmark: ORB extraction, BoW transform, database query and vocabulary load vs DBoW3.

DBoW3 reference (C++, OpenCV 4.6 ORB, built on this machine class, 300 real 640 x 480 photos,
issue 6): ORB 2.9 ms per image; transform of 500 features 0.40 ms (k=10 L=5, 67,919 words) and
0.17 ms (k=10 L=3); query from features 0.78 ms over 300 entries; load of the 68k-word binary
vocabulary 16 ms uncompressed, 31 ms compressed.

symloc's setup: ORB on 640 x 480 rescaled crops of the bundled scikit-image photographs (and a
simulator view); transform with *full* synthetic trees (k=10, L=5: 100,000 words; L=3: 1,000
words: every feature descends all L levels, the worst case) and with the shipped k=10 L=5
vocabulary (76,384 words, trained like DBoW3's); the database is a :class:`VisualMap` of
75 places x 4 images = 300 entries with real BoW vectors; "query" scores one BoW vector against all 300 (vectors cached in memory after the
first query), "query from features" adds the transform. Loads use the native binary format.
Medians over many repeats, ms.

With ``--dbow3 CMD`` (the driver of ``benchmarks/peers/dbow3``, built from DBoW3's source), the
transform is also measured against DBoW3 in the same run, on the same vocabularies and the
descriptors of 12 of the photos, and the BoW vectors of the two are compared.

``--results PATH`` also writes every row (symloc's figure, the DBoW3 figure it is compared with
and whether that was measured in this run or is the stored reference above) as a results file
with the command, commit, date, machine and load (the README's:
``docs/results/bench_vision.json``).

Run: ``python benchmarks/bench_vision.py [--repeats R] [--clock wall|cpu] [--dbow3 CMD]
[--results PATH]``
"""

from __future__ import annotations

import argparse
import math
import shlex
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import skimage.data

from symloc.vision.default_vocabulary import default_vocabulary
from symloc.vision.orb import OrbExtractor
from symloc.vision.visual_map import PlaceImage, VisualMap
from symloc.vision.vocabulary import Vocabulary, load_vocabulary, save_vocabulary

DBOW3_MS = {
    "orb": 2.9,
    "transform_L5": 0.40,
    "transform_L3": 0.17,
    "query_from_features": 0.78,
    "load": 16.0,
    "load_compressed": 31.0,
}

PHOTOS = (
    "astronaut",
    "coffee",
    "chelsea",
    "rocket",
    "hubble_deep_field",
    "immunohistochemistry",
    "camera",
    "coins",
    "moon",
    "brick",
    "grass",
    "gravel",
)


#: The clock of every figure: ``time.perf_counter`` (wall, default) or ``time.process_time``
#: (this process's CPU time, which waiting for a core on a loaded machine does not inflate).
CLOCK: Callable[[], float] = time.perf_counter

#: Every printed row, for ``--results``: ``what``, ``symloc_ms``, ``dbow3_ms`` (or None),
#: ``dbow3`` (``"same run"`` or ``"stored"``), ``ratio``.
ROWS: list[dict[str, Any]] = []


def median_ms(fn: Callable[[], object], repeats: int) -> float:
    """Median time [ms] of ``fn()`` over ``repeats`` calls after one warm-up call (:data:`CLOCK`)."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = CLOCK()
        fn()
        times.append(CLOCK() - t0)
    return 1000.0 * float(np.median(times))


def images_640x480(n: int, rng: np.random.Generator) -> list[np.ndarray]:
    srcs = [getattr(skimage.data, p)() for p in PHOTOS]
    out = []
    for i in range(n):
        img = srcs[i % len(srcs)]
        h, w = img.shape[:2]
        s = rng.uniform(0.6, 1.0)
        ch, cw = int(h * s), int(w * s)
        y, x = rng.integers(0, h - ch + 1), rng.integers(0, w - cw + 1)
        out.append(cv2.resize(img[y : y + ch, x : x + cw], (640, 480)))
    return out


def full_tree(k: int, L: int, rng: np.random.Generator) -> Vocabulary:
    n = (k ** (L + 1) - 1) // (k - 1)
    parent = np.concatenate([[-1], (np.arange(1, n) - 1) // k])
    desc = rng.integers(0, 256, (n, 32), dtype=np.uint8)
    idf = np.log(300.0 / rng.integers(1, 300, n))  # idf-like weights: ln(N / N_i), N = 300 images
    return Vocabulary(k, L, "tf-idf", "l1", parent, desc, idf)


def orb_breakdown(ext: OrbExtractor, imgs: list[np.ndarray], repeats: int) -> None:
    """Where ORB's time goes: grey conversion, OpenCV itself (1 vs default threads, interleaved
    so that the machine's load hits both alike), our keypoint conversion, and the fastest run
    (a load-independent lower bound)."""
    from symloc.vision.orb import to_grey_uint8

    greys = [to_grey_uint8(i) for i in imgs]
    row(
        "  of which grey conversion (cvtColor)", median_ms(lambda: to_grey_uint8(imgs[0]), 50), None
    )
    default_threads = cv2.getNumThreads()
    times: dict[int, list[float]] = {1: [], default_threads: []}
    n_rounds = max(3, repeats // 10)
    for _ in range(n_rounds):
        for th in times:
            cv2.setNumThreads(th)
            for g in greys:
                t0 = CLOCK()
                ext._orb.detectAndCompute(g, None)
                times[th].append(1000.0 * (CLOCK() - t0))
    cv2.setNumThreads(default_threads)
    for th, t in times.items():
        row(f"  OpenCV detectAndCompute, {th} thread(s)", float(np.median(t)), DBOW3_MS["orb"])
    kps, _ = ext._orb.detectAndCompute(greys[0], None)
    from symloc.vision.orb import _KP_ATTRS, _KP_DTYPE

    row(
        f"  keypoint conversion ({len(kps)} keypoints)",
        median_ms(
            lambda: (
                cv2.KeyPoint_convert(kps),
                np.fromiter(map(_KP_ATTRS, kps), dtype=_KP_DTYPE, count=len(kps)),
            ),
            50,
        ),
        None,
    )
    fastest = min(min(t) for t in times.values())
    row("  OpenCV detectAndCompute, fastest run", fastest, DBOW3_MS["orb"])


def same_run_rows(
    cmd: str, voc: Vocabulary, label: str, images: list[np.ndarray], repeats: int
) -> None:
    """DBoW3 and symloc transforming the same descriptors with the same vocabulary.

    The vocabulary goes to DBoW3 as a DBoW2 text file (DBoW3 keeps its weights as float),
    the descriptors ``(N, 32)`` of each image as a binary file; ``cmd`` is the driver built by
    ``benchmarks/peers/dbow3/build.sh``. Both sides: median CPU time [ms] of one transform over
    ``repeats`` transforms of each image. Also checks that the BoW vectors agree: the same
    words, values equal to 1e-6 (relative, the float weights).
    """
    with tempfile.TemporaryDirectory() as tmp:
        voc_txt = Path(tmp) / "voc.txt"  # DBoW3 reads a text vocabulary by its .txt name
        voc.save_dbow2_text(voc_txt)
        desc_bin = Path(tmp) / "desc.bin"
        with desc_bin.open("wb") as fh:
            fh.write(np.int32(len(images)).tobytes())
            for d in images:
                fh.write(np.int32(d.shape[0]).tobytes())
                fh.write(np.ascontiguousarray(d, np.uint8).tobytes())
        out_txt = Path(tmp) / "bow.txt"
        res = subprocess.run(
            [*shlex.split(cmd), str(voc_txt), str(desc_bin), str(repeats), str(out_txt)],
            capture_output=True,
            text=True,
            check=True,
        )
        figures = dict(line.split() for line in res.stdout.splitlines() if line.strip())
        peer_ms = float(figures["transform_ms"])
        agree = 0
        for d, line in zip(images, out_txt.read_text().splitlines(), strict=True):
            pairs = [item.split(":") for item in line.split()]
            words = np.array([int(w) for w, _ in pairs], np.int32)
            values = np.array([float(v) for _, v in pairs])
            bow = voc.bow(d)
            agree += bool(
                np.array_equal(bow.words, words)
                and np.allclose(bow.values, values, rtol=1e-6, atol=0.0)
            )
    times = []
    for d in images:  # as the driver: one warm-up, then the timed transforms
        voc.transform(d)
        for _ in range(repeats):
            t0 = CLOCK()
            voc.transform(d)
            times.append(CLOCK() - t0)
    ours = 1000.0 * float(np.median(times))
    row(
        f"transform, {label}, DBoW3 same run",
        ours,
        peer_ms,
        same_run=True,
        vocabulary=label,
        images=len(images),
        bow_vectors_equal=agree,
    )
    print(f"  ({len(images)} images; BoW vectors agreeing with DBoW3's: {agree}/{len(images)})")


def row(name: str, ours: float, ref: float | None, *, same_run: bool = False, **extra: Any) -> None:
    """Print one row (symloc's figure [ms], DBoW3's and their ratio) and keep it in
    :data:`ROWS`; ``same_run``: DBoW3's figure was measured in this run (else the stored one)."""
    if ref is None:
        print(f"{name:<46}{ours:>10.3f}{'':>10}{'':>9}")
    else:
        print(f"{name:<46}{ours:>10.3f}{ref:>10.2f}{ours / ref:>8.2f}x")
    ROWS.append(
        {
            "what": name,
            "symloc_ms": round(ours, 5),
            "dbow3_ms": None if ref is None else round(ref, 5),
            "dbow3": None if ref is None else ("same run" if same_run else "stored"),
            "ratio": None if ref is None else round(ours / ref, 4),
            **extra,
        }
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=50)
    ap.add_argument(
        "--clock",
        choices=("wall", "cpu"),
        default="wall",
        help="wall: time.perf_counter; cpu: time.process_time (this process's CPU time)",
    )
    ap.add_argument(
        "--dbow3",
        metavar="CMD",
        help="DBoW3 driver (benchmarks/peers/dbow3/build.sh): time its transform in this run",
    )
    ap.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write a results file (the README's: docs/results/bench_vision.json)",
    )
    args = ap.parse_args()
    from symloc.bench.provenance import RunClock

    clock = RunClock()
    global CLOCK
    CLOCK = time.process_time if args.clock == "cpu" else time.perf_counter
    if args.dbow3 and args.clock != "cpu":
        ap.error("--dbow3: the driver measures CPU time; add --clock cpu")
    rng = np.random.default_rng(0)
    r = args.repeats
    ext = OrbExtractor()
    imgs = images_640x480(60, rng)
    import os

    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    print(
        f"# bench_vision: repeats {r}, seed 0, clock {args.clock}, cv2 {cv2.__version__},"
        f" numpy {np.__version__}"
    )
    print(f"# machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    print(f"{'':<46}{'symloc':>10}{'DBoW3':>10}{'ratio':>9}")
    print(f"{'(ms, median)':<46}")

    orb_t = []
    feats = []
    for img in imgs:
        orb_t.append(median_ms(lambda img=img: ext.extract(img), 3))
        feats.append(ext.extract(img))
    row("ORB, 500 features, 640x480 colour photo", float(np.median(orb_t)), DBOW3_MS["orb"])
    orb_breakdown(ext, imgs[:12], r)
    try:
        import math as _m

        from symloc.sim.camera import Camera
        from symloc.sim.rooms import build_room

        room = build_room("square", 3 / _m.sqrt(2))
        view = Camera().render(room.world, [room.center[0], room.center[1], 0.0], rng=0)
        row("ORB, simulator view 640x480", median_ms(lambda: ext.extract(view), r), DBOW3_MS["orb"])
    except ImportError:
        pass

    d500 = next(f.descriptors for f in feats if len(f) == 500)
    voc5 = full_tree(10, 5, rng)
    voc3 = full_tree(10, 3, rng)
    shipped = default_vocabulary()
    vocs = (
        ("k=10 L=5 (100k words)", voc5, DBOW3_MS["transform_L5"]),
        ("k=10 L=3 (1k words)", voc3, DBOW3_MS["transform_L3"]),
        (f"shipped k=10 L=5 ({shipped.n_words} words)", shipped, DBOW3_MS["transform_L5"]),
    )
    for label, voc, stored in vocs:
        row(
            f"transform 500 features, {label}",
            median_ms(lambda v=voc: v.transform(d500), r),
            stored,
        )
    if args.dbow3:
        images = [f.descriptors for f in feats[:12]]
        for label, voc, _stored in vocs:
            same_run_rows(args.dbow3, voc, label, images, r)

    with tempfile.TemporaryDirectory() as tmp:
        vm = VisualMap(Path(tmp) / "map.db")
        bows = []
        for p in range(75):
            images = []
            for j in range(4):
                f = feats[(4 * p + j) % len(feats)]
                b = voc5.bow(f.descriptors)
                bows.append(b)
                images.append(PlaceImage(j, -j * math.pi / 2, f, b))
            vm.add_place(kind="square", order=4, gv_distance=1.0 + p, pose=[0, 0, 0], images=images)
        q = voc5.bow(d500)
        row("database query, 300 entries (BoW scoring)", median_ms(lambda: vm.query(q), r), None)
        row(
            "query from features, 300 entries (L=5)",
            median_ms(lambda: vm.query(voc5.bow(d500)), r),
            DBOW3_MS["query_from_features"],
        )
        vm.close()

        p5 = Path(tmp) / "v5.symvoc"
        p5z = Path(tmp) / "v5z.symvoc"
        save_vocabulary(voc5, p5)
        save_vocabulary(voc5, p5z, compress=True)
        row(
            "load k=10 L=5 (111k nodes, 100k words)",
            median_ms(lambda: load_vocabulary(p5), max(5, r // 5)),
            DBOW3_MS["load"],
        )
        row(
            "load k=10 L=5, zlib-compressed",
            median_ms(lambda: load_vocabulary(p5z), max(5, r // 5)),
            DBOW3_MS["load_compressed"],
        )
        row(
            f"load shipped k=10 L=5 ({shipped.n_words} words)",
            median_ms(lambda: load_vocabulary(shipped_path()), max(5, r // 5)),
            DBOW3_MS["load"],
        )
        voc6 = full_tree(10, 6, rng)
        p6 = Path(tmp) / "v6.symvoc"
        save_vocabulary(voc6, p6)
        del voc6
        row("load k=10 L=6 (1.1M nodes, 1M words)", median_ms(lambda: load_vocabulary(p6), 5), None)
    print(
        "(DBoW3's L=5 vocabulary: 67,919 trained words; the synthetic trees are full, the worst "
        "case; the shipped one is trained; the machine load inflates every figure alike)"
    )
    if args.results is not None:
        from symloc.bench.provenance import peer_source
        from symloc.bench.results_file import write_bench_results

        settings = {
            "repeats": r,
            "clock": args.clock,
            "seed": 0,
            "dbow3": (
                peer_source(args.dbow3, "the driver of benchmarks/peers/dbow3 (rmsalinas/DBow3)")
                if args.dbow3
                else None
            ),
            "opencv": cv2.__version__,
            "numpy": np.__version__,
        }
        written = write_bench_results(
            args.results,
            clock=clock,
            settings=settings,
            figures={"rows": ROWS, "stored_dbow3_ms": DBOW3_MS},
        )
        print(f"wrote {written}")
    return 0


def shipped_path() -> Path:
    from symloc.vision.default_vocabulary import DEFAULT_VOCABULARY_PATH

    return DEFAULT_VOCABULARY_PATH


if __name__ == "__main__":
    raise SystemExit(main())
