"""Build the per-scan kernels ahead of time.

The build normally happens at install: ``pip install .`` (or ``pip install -e .``) runs the
package's ``setup.py``, which asks :func:`extension` for a setuptools extension and builds it
beside :mod:`symloc.mcl.aot` when numba's :mod:`numba.pycc` and a C compiler are there (10-20 s
of CPU). Without them, or if the build fails, the install goes on without it and the kernels
run through numba's JIT (:mod:`symloc.mcl.aot` logs that once per process).

``python -m symloc.mcl.aot_build [--out DIR]`` builds it again by hand (after an edit of
:mod:`symloc.mcl.kernels`, whose stale build is then not loaded; or after installing a
compiler): the kernels of :data:`symloc.mcl.aot.SIGNATURES`, compiled from
:mod:`symloc.mcl.kernels`' Python definitions into the extension
:func:`symloc.mcl.aot.module_name` beside :mod:`symloc.mcl.aot`, which a tracking process then
loads instead of numba (see there).

This module imports nothing of symloc but :mod:`symloc.mcl.aot`, :mod:`symloc.mcl.kernels` and
:mod:`symloc.errors` (the install's build environment has numba and NumPy, not the package's
other dependencies).
"""

from __future__ import annotations

import argparse
import importlib
import logging
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from symloc.errors import SymlocError
from symloc.mcl import aot
from symloc.mcl.aot import PREFIX, SIGNATURES, module_name, numba_signature

__all__ = ["build", "compiler", "extension", "main", "release_gil", "remove_stale"]

_LOG = logging.getLogger(__name__)


def _pycc() -> tuple[Any, Any]:
    """numba's :mod:`numba.pycc` and its compiler module (pycc's pending-deprecation notice
    silenced)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pycc: Any = importlib.import_module("numba.pycc")
        pycc_compiler: Any = importlib.import_module("numba.pycc.compiler")
    return pycc, pycc_compiler


def compiler() -> Any:
    """numba's :class:`numba.pycc.CC` for :func:`module_name`'s extension, with every kernel of
    :data:`SIGNATURES` exported from :mod:`symloc.mcl.kernels`' Python definitions, for this
    machine's CPU (``target_cpu = "host"``, as numba's JIT). Imports numba."""
    pycc, _ = _pycc()
    from symloc.mcl import kernels

    kernels.jit_callees()  # the kernels they call, as numba's dispatchers
    cc = pycc.CC(module_name())
    cc.target_cpu = "host"
    cc.verbose = False
    for kernel, (ret, args) in SIGNATURES.items():
        cc.export(kernel, numba_signature(ret, args))(getattr(kernels, kernel).py_func)
    return cc


@contextmanager
def release_gil() -> Iterator[None]:
    """While pycc compiles inside this block, its functions release the GIL, as the JIT
    kernels do (pycc's default flags hold it; :func:`symloc.mcl.kernels.split_over_threads`
    runs the kernels on several cores)."""
    _, pycc_compiler = _pycc()
    base_flags = pycc_compiler.Flags

    class _NoGilFlags(base_flags):  # type: ignore[misc, valid-type]
        def __init__(self, *a: Any, **k: Any) -> None:
            super().__init__(*a, **k)
            self.release_gil = True

    pycc_compiler.Flags = _NoGilFlags
    try:
        yield
    finally:
        pycc_compiler.Flags = base_flags


def remove_stale(folder: Path) -> list[Path]:
    """Remove the builds in ``folder`` made for other kernels' sources (other hashes than
    :func:`module_name`'s); returns them."""
    name = module_name()
    gone = []
    for old in Path(folder).glob(PREFIX + "*"):
        if not old.name.startswith(name + "."):
            old.unlink()
            gone.append(old)
    return gone


def build(out_dir: Path | None = None) -> Path:
    """Compile the kernels of :data:`SIGNATURES` into :func:`module_name`'s extension in
    ``out_dir`` (default: beside :mod:`symloc.mcl.aot`, where it is loaded from); returns its
    path. Removes older builds there. Needs numba's :mod:`numba.pycc` and a C compiler; takes
    10-20 s of CPU."""
    folder = Path(aot.__file__).parent if out_dir is None else Path(out_dir)
    folder.mkdir(parents=True, exist_ok=True)
    cc = compiler()
    cc.output_dir = str(folder)
    with release_gil():
        cc.compile()
    built = sorted(folder.glob(module_name() + ".*"))
    if not built:
        raise SymlocError(f"numba.pycc wrote no {module_name()} extension into {folder}")
    remove_stale(folder)
    _LOG.info("built %s", built[0])
    return built[0]


def extension() -> Any:
    """A setuptools extension that builds the kernels at install (``setup.py``'s
    ``ext_modules``): numba's ``CC.distutils_extension()`` of :func:`compiler`, named
    ``symloc.mcl.<module_name()>``. Its ``prepare(build_ext)`` must run before setuptools'
    ``build_ext.build_extension`` (it compiles the kernels into the object files to link,
    GIL released)."""
    cc = compiler()
    ext = cc.distutils_extension()
    ext.name = f"symloc.mcl.{module_name()}"

    def prepare(cmd: Any) -> None:
        with release_gil():
            ext._prepare_object_files(cmd)

    ext.prepare = prepare
    return ext


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m symloc.mcl.aot_build [--out DIR]``: build the per-scan kernels."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="folder (default: the package's)")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    build(args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
