"""Fuzz: thousands of generated bad inputs to every file loader, every command and the node.

Each input may only end in a symloc error (or be accepted); anything else escaping is a failure,
as is an input running longer than :data:`fuzz_targets.TIME_BOUND` (a hang). Hypothesis runs
derandomized, so CI sees the same inputs every time. The number of inputs per target is at the
top (``EXAMPLES``); ``test_fuzz_totals`` checks they add up to at least 5,000. Peak memory of the
inputs that could allocate by a declared size (image and map headers, compression bombs) is
checked in a subprocess: ``test_big_inputs_stay_under_500_mb``.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fuzz_targets import (
    apply_db_mutations,
    bag_mutations,
    carmen_logs,
    command_lines,
    counts,
    db_mutations,
    feed,
    guard,
    image_bytes,
    load_map_file,
    load_vocabulary_file,
    loosen,
    make_garbage_files,
    map_files,
    mutate_bag,
    node_messages,
    params_yaml,
    read_bag_skip,
    read_carmen_file,
    read_visual_map,
    vocabulary_files,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

#: Generated inputs per target (each a hypothesis example; node sequences hold 25 messages).
EXAMPLES = {
    "map files": 450,
    "images": 400,
    "vocabularies": 450,
    "carmen logs": 400,
    "visual maps": 220,
    "bags": 120,
    "node params": 300,
    "node messages": 100,
    "commands": 420,
    "output paths": 150,
    "missing data": 120,
    "numeric bounds": 150,
    "special files": 120,
}
#: ``benchmarks/fuzz_report.py --scale K`` runs K times as many inputs per target.
SCALE = float(os.environ.get("SYMLOC_FUZZ_SCALE", "1"))
EXAMPLES = {k: max(1, round(v * SCALE)) for k, v in EXAMPLES.items()}
NODE_SEQUENCE = 25


def fuzz_settings(n: int) -> Any:
    return settings(
        max_examples=n,
        derandomize=True,
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )


#: ``benchmarks/fuzz_report.py`` sets this to count escapes instead of failing on the first.
COUNT_ONLY = os.environ.get("SYMLOC_FUZZ_COUNT_ONLY") == "1"


def _no_escape(outcome: str) -> None:
    if not COUNT_ONLY:
        assert not outcome.startswith("escape"), outcome


# ----------------------------------------------------------------------- file loaders


def test_map_files(tmp_path_factory: pytest.TempPathFactory) -> None:
    folder = tmp_path_factory.mktemp("maps")

    @fuzz_settings(EXAMPLES["map files"])
    @given(map_files())
    def run(case: tuple[str, bytes]) -> None:
        _no_escape(guard("map files", lambda: load_map_file(folder, *case)))

    run()


def test_images(tmp_path_factory: pytest.TempPathFactory) -> None:
    from types import SimpleNamespace

    from symloc.msgs.image import compressed_image_from_msg, image_from_msg
    from symloc.vision.image_files import read_image

    folder = tmp_path_factory.mktemp("images")

    @fuzz_settings(EXAMPLES["images"])
    @given(
        image_bytes(),
        st.sampled_from(["file", "compressed", "raw"]),
        st.integers(-2, 70000),
        st.integers(-2, 70000),
        st.sampled_from(["rgb8", "mono16", "bgra8", "8UC3", "x"]),
    )
    def run(data: bytes, how: str, h: int, w: int, enc: str) -> None:
        if how == "file":
            p = folder / "i.img"
            p.write_bytes(data)
            fn: Any = lambda: read_image(p)  # noqa: E731
        elif how == "compressed":
            fn = lambda: compressed_image_from_msg(SimpleNamespace(format="png", data=data))  # noqa: E731
        else:
            msg = SimpleNamespace(height=h, width=w, step=3 * w, encoding=enc, data=data)
            fn = lambda: image_from_msg(msg)  # noqa: E731
        _no_escape(guard("images", fn))

    run()


def test_vocabularies(tmp_path_factory: pytest.TempPathFactory) -> None:
    folder = tmp_path_factory.mktemp("voc")

    @fuzz_settings(EXAMPLES["vocabularies"])
    @given(vocabulary_files())
    def run(case: tuple[str, bytes]) -> None:
        _no_escape(guard("vocabularies", lambda: load_vocabulary_file(folder, *case)))

    run()


def test_carmen_logs(tmp_path_factory: pytest.TempPathFactory) -> None:
    folder = tmp_path_factory.mktemp("carmen")

    @fuzz_settings(EXAMPLES["carmen logs"])
    @given(carmen_logs())
    def run(case: tuple[str, bytes]) -> None:
        _no_escape(guard("carmen logs", lambda: read_carmen_file(folder, *case)))

    run()


def _valid_visual_map(path: Path) -> Path:
    from symloc.vision.bow import BowVector
    from symloc.vision.orb import OrbFeatures
    from symloc.vision.visual_map import PlaceImage, VisualMap

    rng = np.random.default_rng(0)
    images = []
    for j in range(4):
        kp = np.column_stack([rng.uniform(0, 640, (30, 2)), rng.uniform(5, 30, (30, 4))])
        kp = kp.astype(np.float32)
        desc = rng.integers(0, 256, (30, 32), dtype=np.uint8)
        feats = OrbFeatures.from_arrays(kp, desc, (640, 480))
        words = np.unique(rng.integers(0, 1000, 20)).astype(np.int32)
        bow = BowVector(words, np.full(words.size, 1.0 / words.size))
        img = rng.integers(0, 256, (24, 32, 3), dtype=np.uint8) if j == 0 else None
        images.append(PlaceImage(j, -j * math.pi / 2, feats, bow, img))
    with VisualMap(path) as vm:
        vm.add_place(kind="square", order=4, gv_distance=2.1, pose=[1, 2, 0.3], images=images)
        vm.set_meta("vocabulary", "default")
    return path


def test_visual_maps(tmp_path_factory: pytest.TempPathFactory) -> None:
    folder = tmp_path_factory.mktemp("vmap")
    good_path = _valid_visual_map(folder / "good.db")
    loosen(good_path)
    good = good_path.read_bytes()

    @fuzz_settings(EXAMPLES["visual maps"])
    @given(db_mutations())
    def run(mutations: list[tuple[str, Any]]) -> None:
        path = folder / "m.db"
        for readonly in (True, False):
            path.write_bytes(good)
            for extra in folder.glob("m.db-*"):
                extra.unlink()
            apply_db_mutations(path, mutations)
            _no_escape(guard("visual maps", lambda ro=readonly: read_visual_map(path, ro)))

    run()


@pytest.fixture(scope="module")
def small_bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    return build_small_bags(tmp_path_factory.mktemp("bags"))


def build_small_bags(folder: Path) -> dict[str, Path]:
    """A small valid bag in each format: map, 20 odometry + scans, two images."""
    from symloc.grid import OccupancyGrid
    from symloc.io.rosbag import BagWriter
    from symloc.odometry import OdometryReading
    from symloc.scan import LaserScan

    out = {}
    for fmt in ("ros2", "mcap", "ros1"):
        path = folder / (f"b_{fmt}" + (".bag" if fmt == "ros1" else ""))
        with BagWriter(path, fmt) as w:
            w.write_map(OccupancyGrid(np.zeros((20, 20), np.int8), 0.05), 0.0)
            for i in range(20):
                t = 1 + 0.1 * i
                w.write_odometry(OdometryReading(np.array([0.01 * i, 0, 0]), t))
                ranges = np.full(90, 2.0)
                w.write_scan(LaserScan(-math.pi, 2 * math.pi / 90, 0.1, 8, ranges, stamp=t))
                if i % 10 == 0:
                    w.write_image(np.zeros((12, 16, 3), np.uint8), t)
        out[fmt] = path
    return out


def test_bags(tmp_path_factory: pytest.TempPathFactory, small_bags: dict[str, Path]) -> None:
    import shutil
    import warnings

    folder = tmp_path_factory.mktemp("badbags")

    @fuzz_settings(EXAMPLES["bags"])
    @given(bag_mutations())
    def run(case: tuple[str, str, int, bytes]) -> None:
        fmt, how, seed, data = case
        dst = folder / ("x.bag" if fmt == "ros1" else "x")
        if dst.is_dir():
            shutil.rmtree(dst)
        elif dst.exists():
            dst.unlink()
        path = mutate_bag(small_bags[fmt], dst, how, seed, data)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            _no_escape(guard("bags", lambda: read_bag_skip(path)))

    run()


def test_node_params() -> None:
    from symloc.ros.params import NodeParams

    @fuzz_settings(EXAMPLES["node params"])
    @given(params_yaml())
    def run(text: str) -> None:
        _no_escape(guard("node params", lambda: NodeParams.from_yaml(text)))

    run()


# ----------------------------------------------------------------------- the node


def test_node_messages_never_escape_and_the_node_recovers() -> None:
    """Every message of a garbage sequence is survived (no exception at all leaves NodeCore),
    every scan gets a status, and good messages afterwards are used within 5 scans."""
    from symloc.grid import OccupancyGrid
    from symloc.mcl.params import AmclParams
    from symloc.odometry import OdometryReading
    from symloc.ros.core import NodeCore
    from symloc.ros.params import NodeParams
    from symloc.scan import LaserScan

    d = np.zeros((40, 40), np.int8)
    d[[0, -1], :] = 100
    d[:, [0, -1]] = 100
    d[5:15, 5:8] = 100
    grid = OccupancyGrid(d, 0.05)
    params = NodeParams(amcl=AmclParams(max_particles=200, min_particles=50))
    base = 1000.0
    pose = np.array([1.0, 1.0, 0.0])

    def good(core: NodeCore, t: float) -> bool:
        core.add_odometry(OdometryReading(pose, t))
        ranges = np.full(36, 0.9)
        out = core.add_scan(LaserScan(-math.pi, 2 * math.pi / 36, 0.1, 8.0, ranges, stamp=t))
        return out is not None and bool(getattr(out, "used", True))

    @fuzz_settings(EXAMPLES["node messages"])
    @given(st.lists(node_messages(base), min_size=NODE_SEQUENCE, max_size=NODE_SEQUENCE))
    def run(messages: list[tuple[str, Any]]) -> None:
        core = NodeCore(params)
        core.set_map(grid)
        for i in range(3):
            assert good(core, base - 1.0 + 0.1 * i)
        for kind, msg in messages:
            results: list[Any] = []

            def one(k: str = kind, m: Any = msg, out: list[Any] = results) -> None:
                out.append(feed(core, k, m))
                if k == "scan" and not (out[0] is not None and out[0].status["status"][0]):
                    raise AssertionError("a scan without a status")

            _no_escape(guard("node messages", one, allowed=()))

        def recovers() -> None:
            used = [good(core, base + 2.0 + 0.1 * i) for i in range(8)]
            if True not in used[:5]:
                raise AssertionError(f"not used within 5 scans: {used}; {dict(core.dropped)}")

        _no_escape(guard("node recovery", recovers, allowed=()))

    run()


# ----------------------------------------------------------------------- the command line


def test_commands(tmp_path_factory: pytest.TempPathFactory) -> None:
    from fuzz_targets import command_leaves, run_command

    folder = tmp_path_factory.mktemp("cli")
    files = make_garbage_files(folder)

    @fuzz_settings(EXAMPLES["commands"])
    @given(command_lines(command_leaves(), files))
    def run(argv: list[str]) -> None:
        make_garbage_files(folder)  # fresh garbage for every command (some commands write)
        _no_escape(guard("commands", lambda: run_command(argv), allowed=()))

    run()


def test_output_paths(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Every output option of every command, given a path of the wrong kind (a file for a
    folder, a folder for a file, below a file, /dev/null, a FIFO, empty, NUL, a name over 255
    bytes): a usage error naming the option and the path, before anything runs."""
    from fuzz_targets import command_leaves, output_options, output_path_cases, run_output_case

    folder = tmp_path_factory.mktemp("outputs")
    leaves = command_leaves()
    outputs = output_options(leaves)
    assert len(outputs) >= 40, "every command's --out and --json, and the other outputs"

    @fuzz_settings(EXAMPLES["output paths"])
    @given(output_path_cases(outputs, folder))
    def run(case: tuple[list[str], str, str]) -> None:
        argv, name, value = case
        _no_escape(guard("output paths", lambda: run_output_case(argv, name, value, leaves)))
        assert (folder / "a_file").read_text() == "keep me"

    run()


def test_missing_data(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Commands pointed at data sets that are not there (missing, empty, a FIFO, /dev/zero,
    logs of other names): a non-zero exit and a message, never "skipping" and exit 0."""
    from fuzz_targets import missing_data_cases, run_missing_data

    folder = tmp_path_factory.mktemp("nodata")

    @fuzz_settings(EXAMPLES["missing data"])
    @given(missing_data_cases(folder))
    def run(argv: list[str]) -> None:
        _no_escape(guard("missing data", lambda: run_missing_data(argv)))

    run()


def test_numeric_bounds() -> None:
    """Every bounded numeric option beyond its bound: a usage error naming the option."""
    from fuzz_targets import (
        bounded_options,
        command_leaves,
        out_of_bounds_cases,
        run_out_of_bounds,
    )

    bounded = bounded_options(command_leaves())
    assert len(bounded) >= 40

    @fuzz_settings(EXAMPLES["numeric bounds"])
    @given(out_of_bounds_cases(bounded))
    def run(case: tuple[list[str], str]) -> None:
        _no_escape(guard("numeric bounds", lambda: run_out_of_bounds(*case)))

    run()


def test_special_files(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Every file loader of the library given a FIFO, /dev/zero, /dev/urandom, /dev/null, a
    folder, a link to a FIFO or nothing (also as the image a map YAML names): a symloc error
    at once, never a blocked open or an endless read."""
    from fuzz_targets import load_special, special_file_cases

    folder = tmp_path_factory.mktemp("special")

    @fuzz_settings(EXAMPLES["special files"])
    @given(special_file_cases(folder))
    def run(case: tuple[str, Path]) -> None:
        _no_escape(guard("special files", lambda: load_special(*case)))

    run()


# ----------------------------------------------------------------------- totals and memory


def test_fuzz_totals() -> None:
    """At least 5,000 generated inputs across the targets above (when they all ran)."""
    if not set(EXAMPLES) <= set(counts):
        pytest.skip(f"not every fuzz target ran in this session: {sorted(counts)}")
    total = sum(sum(c.values()) for c in counts.values())
    lines = [f"{t}: {sum(c.values())} inputs {dict(c)}" for t, c in sorted(counts.items())]
    print("\n".join(lines), f"\ntotal {total}")
    assert counts["node messages"].total() >= EXAMPLES["node messages"] * NODE_SEQUENCE
    assert total >= 5000


BIG_INPUTS = textwrap.dedent(
    r"""
    import gzip, resource, struct, sys, zlib
    from pathlib import Path
    from types import SimpleNamespace
    sys.path.insert(0, sys.argv[2])
    from fuzz_targets import png_header, jpeg_header
    from symloc.errors import SymlocError
    from symloc.grid.map_io import load_map
    from symloc.image_header import read_image_file
    from symloc.io.carmen import read_carmen
    from symloc.msgs.image import compressed_image_from_msg, image_from_msg
    from symloc.vision.vocabulary import load_vocabulary
    folder = Path(sys.argv[1])
    MiB = 1 << 20
    zeros = bytes(MiB)

    def gz(path, head, unit, count):  # written in pieces: this process never holds it
        with gzip.open(path, "wb", compresslevel=1) as fh:
            fh.write(head)
            for _ in range(count):
                fh.write(unit)

    y = folder / "map.yaml"
    y.write_text("image: m.png\nresolution: 0.05\norigin: [0, 0, 0]\n"
                 "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    big_png = png_header(16000, 16000, bytes(249000))
    big_pgm = b"P5\n65535 65535\n65535\n" + bytes(1000)
    (folder / "big.png").write_bytes(big_png)
    z = zlib.compressobj(1)
    stream = b"".join(z.compress(zeros) for _ in range(256)) + z.flush()  # 256 MiB of zeros
    payload = struct.pack("<Q", len(stream)) + stream + bytes(32 * 10)
    head = struct.pack("<8sIIIIIIQIIQ8s", b"SYMLVOC\x00", 1, 10, 5, 0, 0, 32, 10, 1,
                       zlib.crc32(payload) & 0xFFFFFFFF, len(payload), bytes(8))
    (folder / "bomb.symvoc").write_bytes(head + payload)
    del stream, payload
    gz(folder / "bomb.txt.gz", b"10 5 0 0\n", zeros, 64)        # 64 MiB of NUL
    gz(folder / "lines.txt.gz", b"10 5 0 0\n", b"\n" * MiB, 100)  # 100 MiB of newlines
    gz(folder / "bomb.log.gz", b"FLASER ", b"1 " * (MiB // 2), 64)  # one 64 MiB line

    def map_with(data):
        (folder / "m.png").write_bytes(data)
        load_map(y)

    cases = [
        ("map PNG declaring 16000 x 16000", lambda: map_with(big_png)),
        ("map 16-bit PGM declaring 65535 x 65535", lambda: map_with(big_pgm)),
        ("photo PNG declaring 16000 x 16000", lambda: read_image_file(folder / "big.png")),
        ("CompressedImage PNG 16000 x 16000",
         lambda: compressed_image_from_msg(SimpleNamespace(format="png", data=big_png))),
        ("CompressedImage JPEG 65535 x 65535",
         lambda: compressed_image_from_msg(SimpleNamespace(
             format="jpeg", data=jpeg_header(65535, 65535, bytes(1000))))),
        ("Image 100000 x 100000 rgb8", lambda: image_from_msg(SimpleNamespace(
            height=100000, width=100000, step=300000, encoding="rgb8", data=bytes(100)))),
        ("vocabulary whose weights inflate to 256 MiB",
         lambda: load_vocabulary(folder / "bomb.symvoc")),
        ("DBoW2 text .gz: a 64 MiB line", lambda: load_vocabulary(folder / "bomb.txt.gz")),
        ("DBoW2 text .gz of 100 MiB of newlines",
         lambda: load_vocabulary(folder / "lines.txt.gz")),
        ("CARMEN .gz with a 64 MiB line", lambda: read_carmen(folder / "bomb.log.gz")),
    ]

    def peak_kib():
        # VmHWM is this process image's own high-water mark; ru_maxrss also carries the
        # parent's (Linux keeps the forked parent's peak across exec), so a large pytest
        # process would be counted against these inputs.
        try:
            for line in Path("/proc/self/status").read_text().splitlines():
                if line.startswith("VmHWM:"):
                    return float(line.split()[1])
        except OSError:
            pass
        return float(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)

    base = peak_kib()
    for name, fn in cases:
        try:
            fn()
            print("ACCEPTED", name)
        except SymlocError as err:
            print("refused", name, "|", str(err)[:110])
    peak = peak_kib()
    print(f"PEAK_MB {peak / 1024:.1f} BASE_MB {base / 1024:.1f}")
    """
)


def test_big_inputs_stay_under_500_mb(tmp_path: Path) -> None:
    """Inputs that declare huge sizes or inflate enormously, in a fresh process: each is
    refused, and the process's peak resident memory (interpreter and libraries included)
    stays under 500 MB, so no single input came near it."""
    script = tmp_path / "big.py"
    script.write_text(BIG_INPUTS)
    here = Path(__file__).parent
    proc = subprocess.run(
        [sys.executable, str(script), str(tmp_path), str(here)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    report = f"stdout:\n{proc.stdout}\nstderr (end):\n{proc.stderr[-3000:]}"
    assert proc.returncode == 0, report
    lines = proc.stdout.splitlines()
    assert not [line for line in lines if line.startswith("ACCEPTED")], report
    assert sum(line.startswith("refused") for line in lines) == 10, report
    peak_lines = [line for line in lines if line.startswith("PEAK_MB")]
    assert peak_lines, report
    peak = float(peak_lines[-1].split()[1])
    print(proc.stdout)
    assert peak < 500.0, report
