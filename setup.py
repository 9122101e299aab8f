"""Install-time build of symloc's per-scan kernels (everything else is in pyproject.toml).

``pip install .`` and ``pip install -e .`` compile the kernels of the particle filter's per-scan
path ahead of time with numba's :mod:`numba.pycc` (:mod:`symloc.mcl.aot_build`) into an
extension beside :mod:`symloc.mcl.aot`, so that a tracking process does not load numba. It
needs a C compiler. Whatever goes wrong here -- no compiler, no numba in the build
environment, a failed compile -- the install goes on without the extension (pip shows the
reason with ``-v``) and the kernels run through numba's JIT; ``python -m
symloc.mcl.aot_build`` builds it later.
"""

from __future__ import annotations

import sys
import types
from pathlib import Path
from typing import Any

from setuptools import setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent


def _aot_build() -> Any:
    """symloc.mcl.aot_build imported from ``src`` without running the packages' ``__init__``
    (they need dependencies the build environment does not have)."""
    for name in ("symloc", "symloc.mcl"):
        if name not in sys.modules:
            pkg = types.ModuleType(name)
            pkg.__path__ = [str(HERE / "src" / Path(*name.split(".")))]
            sys.modules[name] = pkg
    import symloc.mcl.aot_build as aot_build

    return aot_build


_JIT = (
    "the per-scan kernels will run through numba's JIT (python -m symloc.mcl.aot_build builds"
    " them later)"
)


def _warn(what: str, exc: BaseException, then: str = _JIT) -> None:
    """One line on stderr (pip shows it with ``-v``): what was skipped, why, what follows."""
    print(f"symloc: {what} ({type(exc).__name__}: {exc}); {then}", file=sys.stderr)


def _extensions() -> list[Any]:
    try:
        return [_aot_build().extension()]
    except Exception as exc:  # an optional build never fails the install
        _warn("no ahead-of-time build of the kernels", exc)
        return []


class OptionalBuildExt(build_ext):  # type: ignore[misc]
    """setuptools' build_ext that compiles numba's kernels first and never fails: an
    extension it could not build is left out (with a message on stderr)."""

    def build_extension(self, ext: Any) -> None:
        prepare = getattr(ext, "prepare", None)
        if prepare is not None:
            prepare(self)
        super().build_extension(ext)

    def run(self) -> None:
        try:
            super().run()
        except Exception as exc:  # an optional build never fails the install
            _warn("the kernels' ahead-of-time build failed", exc)
            self.extensions: list[Any] = []

    def get_outputs(self) -> list[str]:
        return [p for p in super().get_outputs() if Path(p).exists()]

    def copy_extensions_to_source(self) -> None:
        """The editable install's copy into ``src/symloc/mcl``, and older builds removed."""
        try:
            super().copy_extensions_to_source()
            if self.extensions:
                _aot_build().remove_stale(HERE / "src" / "symloc" / "mcl")
        except Exception as exc:  # an optional build never fails the install
            _warn("the kernels' ahead-of-time build was not copied into the source tree", exc)


class CompilingBuildPy(build_py):  # type: ignore[misc]
    """setuptools' build_py that, for an editable install, also byte-compiles the package's
    sources in place, as pip does for a regular install (``--compile``, its default): every
    process then loads symloc's modules from ``__pycache__`` instead of compiling them (about
    0.04 s of CPU per process), also where ``PYTHONDONTWRITEBYTECODE`` keeps Python from
    writing them itself. Python checks each file against its source, so an edit is picked up.
    Never fails the install."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            try:
                import compileall

                compileall.compile_dir(str(HERE / "src" / "symloc"), quiet=1)
            except Exception as exc:  # an optional step never fails the install
                _warn("the sources were not byte-compiled", exc, "Python compiles them on import")


if __name__ == "__main__":  # setuptools' build backend runs this file as __main__
    setup(
        ext_modules=_extensions(),
        cmdclass={"build_ext": OptionalBuildExt, "build_py": CompilingBuildPy},
    )
