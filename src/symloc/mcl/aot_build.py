"""Build the per-scan kernels ahead of time: ``python -m symloc.mcl.aot_build [--out DIR]``.

Once per install (it needs numba's :mod:`numba.pycc` and a C compiler; 10-20 s of CPU): the
kernels of :data:`symloc.mcl.aot.SIGNATURES`, compiled from :mod:`symloc.mcl.kernels`' Python
definitions into the extension :func:`symloc.mcl.aot.module_name` beside
:mod:`symloc.mcl.aot`, which a tracking process then loads instead of numba (see there).
"""

from __future__ import annotations

import argparse
import importlib
import logging
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from symloc.errors import SymlocError
from symloc.mcl import aot
from symloc.mcl.aot import PREFIX, SIGNATURES, module_name, numba_signature

__all__ = ["build", "main"]

_LOG = logging.getLogger(__name__)


def build(out_dir: Path | None = None) -> Path:
    """Compile the kernels of :data:`SIGNATURES` into :func:`module_name`'s extension in
    ``out_dir`` (default: beside :mod:`symloc.mcl.aot`, where it is loaded from); returns its
    path. Removes older builds there. Needs numba's :mod:`numba.pycc` and a C compiler; takes
    10-20 s of CPU."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pycc's pending-deprecation notice
        pycc: Any = importlib.import_module("numba.pycc")
        pycc_compiler: Any = importlib.import_module("numba.pycc.compiler")

    from symloc.mcl import kernels

    kernels.jit_callees()  # the kernels they call, as numba's dispatchers
    folder = Path(aot.__file__).parent if out_dir is None else Path(out_dir)
    folder.mkdir(parents=True, exist_ok=True)
    name = module_name()
    cc = pycc.CC(name)
    cc.output_dir = str(folder)
    cc.target_cpu = "host"  # the machine it runs on, as numba's JIT
    cc.verbose = False
    for kernel, (ret, args) in SIGNATURES.items():
        cc.export(kernel, numba_signature(ret, args))(getattr(kernels, kernel).py_func)
    # pycc compiles with default flags, which hold the GIL; the JIT kernels release it
    # (symloc.mcl.kernels.split_over_threads runs them on several cores): the same here.
    base_flags = pycc_compiler.Flags

    class _NoGilFlags(base_flags):  # type: ignore[misc, valid-type]
        def __init__(self, *a: Any, **k: Any) -> None:
            super().__init__(*a, **k)
            self.release_gil = True

    pycc_compiler.Flags = _NoGilFlags
    try:
        cc.compile()
    finally:
        pycc_compiler.Flags = base_flags
    built = sorted(folder.glob(name + ".*"))
    if not built:
        raise SymlocError(f"numba.pycc wrote no {name} extension into {folder}")
    for old in folder.glob(PREFIX + "*"):
        if not old.name.startswith(name + "."):
            old.unlink()
    _LOG.info("built %s", built[0])
    return built[0]


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
