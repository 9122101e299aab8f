"""The per-scan kernels built ahead of time give bit for bit what numba's JIT kernels give."""

from __future__ import annotations

import importlib
import importlib.util
import logging
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
from mcl_fixtures import asymmetric_room, synthetic_scan

from symloc.geometry import compose
from symloc.mcl import Amcl, AmclParams, ConfidenceJudge, aot, aot_build, kernels
from symloc.odometry import OdometryReading


def _per_scan() -> list[aot.Kernel]:
    return [getattr(kernels, name) for name in aot.SIGNATURES]


ROOT = Path(__file__).resolve().parents[2]


def _setup_module() -> ModuleType:
    """The package's setup.py, imported (its ``setup()`` call runs only as ``__main__``)."""
    spec = importlib.util.spec_from_file_location("symloc_setup_py", ROOT / "setup.py")
    assert spec is not None
    assert spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _build_ext(tmp: Path, extensions: list[Any]) -> Any:
    """setup.py's build_ext command over ``extensions``, writing under ``tmp``, run."""
    from setuptools import Distribution

    setup_py = _setup_module()
    dist = Distribution({"name": "symloc", "ext_modules": extensions})
    dist.cmdclass["build_ext"] = setup_py.OptionalBuildExt
    cmd = dist.get_command_obj("build_ext")
    cmd.build_lib = str(tmp / "lib")
    cmd.build_temp = str(tmp / "temp")
    cmd.ensure_finalized()
    cmd.run()
    return cmd


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ModuleType]:
    """A build made as the install makes it (setup.py's build_ext over
    :func:`symloc.mcl.aot_build.extension`) in a temporary folder, imported from there."""
    if importlib.util.find_spec("numba.pycc") is None:  # pragma: no cover - a later numba
        pytest.skip("numba.pycc is not available")
    if shutil.which("cc") is None and shutil.which("gcc") is None:  # pragma: no cover
        pytest.skip("no C compiler")
    tmp = tmp_path_factory.mktemp("aot")
    cmd = _build_ext(tmp, [aot_build.extension()])
    outputs = cmd.get_outputs()
    assert len(outputs) == 1
    path = Path(outputs[0])
    assert path.parent == tmp / "lib" / "symloc" / "mcl"  # where the package loads it from
    assert path.name.startswith(aot.module_name() + ".")
    spec = importlib.util.spec_from_file_location(aot.module_name(), path)
    assert spec is not None
    assert spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    yield mod
    for k in _per_scan():
        k.bind(aot.load())


def _track(seed: int) -> list[tuple[np.ndarray, int, bool]]:
    """A few tracked and judged scans on a small room: estimates, particle counts, verdicts."""
    grid = asymmetric_room()
    params = AmclParams(laser_model_type="likelihood_field_prob", max_particles=3000)
    amcl = Amcl(grid, params, np.random.default_rng(seed))
    judge = ConfidenceJudge(amcl)
    rng = np.random.default_rng(seed + 100)
    true, odom = np.array([5.0, 3.0, 0.3]), np.array([1.0, 1.0, 0.0])
    amcl.initialize_pose(true, np.diag([0.1, 0.1, 0.02]))
    out = []
    for i in range(12):
        res, conf = judge.update(OdometryReading(odom), synthetic_scan(grid, true, rng))
        out.append((res.estimate.copy(), res.particles.shape[0], conf.confident))
        step = np.array([0.3, 0.0, 0.0]) if i % 2 == 0 else np.array([0.0, 0.0, 0.3])
        true, odom = compose(true, step), compose(odom, step)
    assert judge.n_rival_searches >= 1
    return out


def test_the_build_tracks_bit_for_bit_as_the_jit(built: ModuleType) -> None:
    for k in _per_scan():
        k.bind(None)
    jit = _track(3)
    for k in _per_scan():
        k.bind(built)
        assert k.ahead_of_time
    ahead = _track(3)
    for (e1, n1, c1), (e2, n2, c2) in zip(jit, ahead, strict=True):
        np.testing.assert_array_equal(e1, e2)
        assert (n1, c1) == (n2, c2)


def test_arguments_the_build_was_not_made_for_go_to_the_jit(built: ModuleType) -> None:
    from numba.core.errors import TypingError

    k = kernels.endpoint_table_sum
    k.bind(built)
    rng = np.random.default_rng(0)
    table = rng.random(40 * 30).astype(np.float32)
    poses = np.column_stack(
        [rng.uniform(2, 35, 50), rng.uniform(2, 25, 50), rng.uniform(-3, 3, 50)]
    )
    bx = rng.uniform(-3, 3, 7).astype(np.float32)
    by = rng.uniform(-3, 3, 7).astype(np.float32)
    want = np.empty(50)
    k(table, 40, 30, poses, 1.0, bx, by, 0, 50, want)
    strided = np.repeat(bx, 2)[::2]
    for args in (
        (table.astype(np.float64), poses, bx),  # another dtype
        (table, np.asfortranarray(poses), bx),  # not C order
        (table, poses, strided),  # not contiguous
    ):
        got = np.empty(50)
        k(args[0], 40, 30, args[1], 1.0, args[2], by, 0, 50, got)
        np.testing.assert_allclose(got, want, rtol=1e-6)
    read_only = np.empty(50)
    read_only.setflags(write=False)
    with pytest.raises(TypingError):  # the JIT refuses to write it; the build is not called
        k(table, 40, 30, poses, 1.0, bx, by, 0, 50, read_only)


def test_the_module_name_follows_the_kernels_source() -> None:
    name = aot.module_name()
    assert name.startswith("_kernels_aot_")
    assert len(name) == len("_kernels_aot_") + 12
    assert name == aot.module_name()


@pytest.mark.skipif(
    aot.load() is None, reason="no build beside the package (python -m symloc.mcl.aot_build)"
)
def test_with_a_build_a_tracking_process_never_loads_numba() -> None:
    code = (
        "import sys, numpy as np\n"
        f"sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
        "from mcl_fixtures import asymmetric_room, synthetic_scan\n"
        "from symloc.mcl import Amcl, AmclParams, ConfidenceJudge\n"
        "from symloc.odometry import OdometryReading\n"
        "g = asymmetric_room(); a = Amcl(g, AmclParams(), np.random.default_rng(0))\n"
        "j = ConfidenceJudge(a); p = np.array([5.0, 3.0, 0.3])\n"
        "a.initialize_pose(p, np.diag([0.1, 0.1, 0.02]))\n"
        "for i in range(4):\n"
        "    j.update(OdometryReading(p), synthetic_scan(g, p, np.random.default_rng(i)))\n"
        "print('numba' in sys.modules, 'scipy.linalg' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]


def test_a_failed_build_does_not_fail_the_install(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from setuptools import Extension

    broken = Extension("symloc.mcl._kernels_aot_broken", sources=[])

    def prepare(cmd: Any) -> None:
        raise RuntimeError("no compiler here")

    broken.prepare = prepare  # type: ignore[attr-defined]
    cmd = _build_ext(tmp_path, [broken])  # does not raise
    assert cmd.extensions == []
    assert cmd.get_outputs() == []
    assert "the kernels' ahead-of-time build failed (RuntimeError: no compiler here)" in (
        capsys.readouterr().err
    )


def test_without_a_build_the_jit_is_used_and_said_once(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setattr(aot, "_LOADED", [])
    monkeypatch.setattr(aot, "module_name", lambda: "_kernels_aot_000000000000")
    with caplog.at_level(logging.INFO, logger="symloc.mcl.aot"):
        assert aot.load() is None
        assert aot.load() is None
    lines = [r.getMessage() for r in caplog.records if r.name == "symloc.mcl.aot"]
    assert len(lines) == 1
    assert "no ahead-of-time build" in lines[0]
    assert "numba's JIT" in lines[0]


def test_a_build_that_does_not_import_falls_back_to_the_jit(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    def broken(name: str) -> ModuleType:
        raise ImportError(f"{name}: numpy.core.multiarray failed to import")

    monkeypatch.setattr(aot, "_LOADED", [])
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: object())
    monkeypatch.setattr(importlib, "import_module", broken)
    with caplog.at_level(logging.INFO, logger="symloc.mcl.aot"):
        assert aot.load() is None
    assert any("does not load (ImportError" in r.getMessage() for r in caplog.records)


@pytest.mark.parametrize("editable", [True, False])
def test_an_editable_install_byte_compiles_the_sources(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, editable: bool
) -> None:
    from setuptools import Distribution

    setup_py = _setup_module()
    pkg = tmp_path / "src" / "symloc" / "sub"
    pkg.mkdir(parents=True)
    (pkg / "mod.py").write_text("X = 1\n")
    monkeypatch.setattr(setup_py, "HERE", tmp_path)
    dist = Distribution({"name": "symloc"})
    cmd = setup_py.CompilingBuildPy(dist)
    cmd.editable_mode = editable
    cmd.build_lib = str(tmp_path / "lib")
    cmd.ensure_finalized()
    cmd.run()
    compiled = list((pkg / "__pycache__").glob("mod.*.pyc"))
    assert len(compiled) == (1 if editable else 0)
