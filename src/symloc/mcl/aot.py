"""The per-scan kernels built ahead of time: a tracking process that never loads numba.

:mod:`symloc.mcl.kernels` compiles its loops with numba and caches the machine code on disk,
but loading even a cached kernel costs a process about 0.7 s of CPU before its first scan:
numba's import (0.13 s), the typing and lowering registries its first call loads (0.3 s, among
them scipy.linalg for numba's BLAS check) and, at exit, the interpreter's collections over the
~80,000 objects these leave behind (0.2-0.3 s); on the smaller CARMEN logs that is the C++
amcl core's whole run. The install (``pip install .`` or ``pip install -e .``: the package's
``setup.py``, see :mod:`symloc.mcl.aot_build`; it needs a C compiler, and an install without
one goes on without it) compiles the kernels of the per-scan path -- the laser step,
KLD-sampling's stop, clustering, motion sampling and the rival search's scoring -- with
numba's ahead-of-time compiler (:mod:`numba.pycc`) into an extension module beside this file,
from the same Python definitions, for this machine's CPU (``target_cpu = "host"``, as numba's
JIT), the GIL released as the JIT kernels do. :class:`Kernel` then calls it when the arguments
have the types it was built for, and numba's JIT kernel otherwise, which loads numba on first
use. Without a build (or one that does not import) :func:`load` logs one line and every
kernel runs through numba's JIT.

The module's name carries a hash of the kernels' source and signatures
(:func:`module_name`): after an edit of :mod:`symloc.mcl.kernels` a stale build is not loaded
(the JIT kernels run until it is built again). ``SYMLOC_AOT=0`` in the environment ignores a
build (the JIT path alone).

An extension compiled ahead of time checks nothing of its arguments (a float64 array where it
expects float32 is read as float32, out of bounds): :class:`Kernel` checks each array's dtype,
dimensions, C order, alignment and, for the arrays a kernel writes, that they are writeable,
before it calls the build (about a microsecond per call).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import logging
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

__all__ = ["PREFIX", "SIGNATURES", "Kernel", "load", "module_name", "numba_signature"]

_LOG = logging.getLogger(__name__)

#: Per-scan kernel -> (return type, argument types): ``i8`` / ``f8`` scalars (int64, float64),
#: arrays as ``f4[::1]``, ``f8[:, ::1]`` (float32, float64, int64; C order), with a trailing
#: ``!`` on the arrays the kernel writes. Exactly the types the filter and the rival search
#: pass (a call with others goes to numba's JIT kernel).
SIGNATURES: dict[str, tuple[str, tuple[str, ...]]] = {
    "endpoint_table_sum": (
        "void",
        ("f4[::1]", "i8", "i8", "f8[:, ::1]", "f8", "f4[::1]", "f4[::1]", "i8", "i8", "f8[::1]!"),
    ),
    "kld_stop": ("i8", ("f8[:, ::1]", "f8", "f8", "i8", "f8", "f8", "i8", "i8")),
    "bin_components": ("i8", ("f8[:, ::1]", "f8", "f8", "i8", "i8[::1]!")),
    "cluster_sums": ("void", ("f8[:, ::1]", "f8[::1]", "f8", "i8[::1]", "i8", "f8[:, ::1]!")),
    "cluster_moments": (
        "void",
        ("f8[:, ::1]", "f8[::1]", "f8", "i8[::1]", "f8[:, ::1]", "f8[::1]!", "f8[:, ::1]!"),
    ),
    "move_diff": (
        "void",
        ("f8[:, ::1]", "f8[:, ::1]", "f8", "f8", "f8", "f8", "f8", "f8", "f8[:, ::1]!"),
    ),
    "count_within": (
        "void",
        (
            "f4[::1]",
            "i8",
            "i8",
            "f8[:, ::1]",
            "f8",
            "f4[::1]",
            "f4[::1]",
            "f4[::1]",
            "i8",
            "i8",
            "i8",
            "i8",
            "i8",
            "f8[::1]!",
        ),
    ),
}

_NUMBA_TYPES = {"f4": "float32", "f8": "float64", "i8": "int64", "void": "void"}
_DTYPES = {"f4": np.dtype(np.float32), "f8": np.dtype(np.float64), "i8": np.dtype(np.int64)}
#: The extension's module name before the hash of the kernels.
PREFIX = "_kernels_aot_"


def _kernels_source() -> Path:
    return Path(__file__).with_name("kernels.py")


def module_name() -> str:
    """The extension's module name for the current kernels: ``_kernels_aot_`` and 12 hex
    digits of a hash of :mod:`symloc.mcl.kernels`' source and :data:`SIGNATURES`."""
    h = hashlib.sha256(_kernels_source().read_bytes())
    h.update(repr(sorted(SIGNATURES.items())).encode())
    return PREFIX + h.hexdigest()[:12]


def numba_signature(ret: str, args: Sequence[str]) -> str:
    """numba's signature string of a :data:`SIGNATURES` entry."""

    def one(code: str) -> str:
        base, _, dims = code.rstrip("!").partition("[")
        return _NUMBA_TYPES[base] + ("[" + dims if dims else "")

    return f"{one(ret)}({', '.join(one(a) for a in args)})"


_LOADED: list[ModuleType | None] = []


def load() -> ModuleType | None:
    """The extension built for the current kernels, imported once; None if it was not built,
    cannot be imported (both logged once, at INFO: the kernels then run through numba's JIT)
    or ``SYMLOC_AOT=0``."""
    if not _LOADED:
        mod = None
        if os.environ.get("SYMLOC_AOT", "1") != "0":
            full = f"{__package__}.{module_name()}"
            try:
                if importlib.util.find_spec(full) is None:
                    _LOG.info(
                        "per-scan kernels: no ahead-of-time build for this source (%s; made at"
                        " install when a C compiler is there, or by python -m"
                        " symloc.mcl.aot_build): numba's JIT",
                        full,
                    )
                else:
                    mod = importlib.import_module(full)
                    _LOG.debug("per-scan kernels from %s", mod.__file__)
            except Exception as exc:  # a broken build falls back to the JIT
                _LOG.info(
                    "per-scan kernels: the ahead-of-time build %s does not load (%s: %s):"
                    " numba's JIT",
                    full,
                    type(exc).__name__,
                    exc,
                )
                mod = None
        _LOADED.append(mod)
    return _LOADED[0]


def _checker(code: str) -> Callable[[Any], bool]:
    """A test that one argument has the type ``code`` (see :data:`SIGNATURES`)."""
    base, _, dims = code.rstrip("!").partition("[")
    if not dims:
        if base == "i8":
            return lambda v: isinstance(v, (int, np.integer)) and not isinstance(v, bool)
        return lambda v: isinstance(v, (float, int, np.floating, np.integer))
    dtype, ndim, write = _DTYPES[base], dims.count(",") + 1, code.endswith("!")

    def ok(v: Any) -> bool:
        if type(v) is not np.ndarray or v.dtype != dtype or v.ndim != ndim:
            return False
        f = v.flags
        return bool(f.c_contiguous and f.aligned and (f.writeable or not write))

    return ok


class Kernel:
    """One kernel of :mod:`symloc.mcl.kernels`: called through the ahead-of-time build when
    there is one and the arguments fit it, through numba's JIT otherwise (numba is imported
    on the first such call, the dispatcher made then: ``cache=True, nogil=True,
    error_model="numpy"``).

    Parameters
    ----------
    py_func : callable
        The plain-Python definition (what both compile).
    make_jit : callable
        ``make_jit(py_func)`` returns numba's dispatcher (called once, on first need).
    """

    __slots__ = ("__name__", "_aot", "_checks", "_dispatcher", "_make_jit", "py_func")

    def __init__(self, py_func: Callable[..., Any], make_jit: Callable[[Any], Any]) -> None:
        self.py_func = py_func
        self.__name__ = py_func.__name__.removesuffix("_py")
        self._make_jit = make_jit
        self._dispatcher: Any = None
        self._aot: Callable[..., Any] | None = None
        self._checks: tuple[Callable[[Any], bool], ...] = ()
        if self.__name__ in SIGNATURES:
            self.bind(load())

    def bind(self, module: ModuleType | None) -> None:
        """Call this kernel through ``module``'s build of it (an extension made by
        :func:`symloc.mcl.aot_build.build`), or only through numba's JIT (None)."""
        self._aot, self._checks = None, ()
        if module is not None and self.__name__ in SIGNATURES:
            self._aot = getattr(module, self.__name__)
            self._checks = tuple(_checker(c) for c in SIGNATURES[self.__name__][1])

    @property
    def dispatcher(self) -> Any:
        """numba's JIT dispatcher (made, and numba imported, on first use)."""
        if self._dispatcher is None:
            self._dispatcher = self._make_jit(self.py_func)
        return self._dispatcher

    @property
    def ahead_of_time(self) -> bool:
        """Whether an ahead-of-time build of this kernel was loaded."""
        return self._aot is not None

    @property
    def signatures(self) -> list[Any]:
        """The signatures ready to run without compiling: the build's (as its numba
        signature string) and those numba's dispatcher has compiled or loaded."""
        out: list[Any] = []
        if self._aot is not None:
            ret, args = SIGNATURES[self.__name__]
            out.append(numba_signature(ret, args))
        if self._dispatcher is not None:
            out.extend(self._dispatcher.signatures)
        return out

    def __call__(self, *args: Any) -> Any:
        aot = self._aot
        if aot is not None and len(args) == len(self._checks):
            for check, v in zip(self._checks, args, strict=True):
                if not check(v):
                    break
            else:
                return aot(*args)
        return self.dispatcher(*args)
