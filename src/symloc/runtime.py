"""How a symloc process starts: the environment of the command line, the ROS node and the
benchmarks' symloc workers.

symloc's own parallel work runs on its kernels' thread pool (:mod:`symloc.mcl.kernels`); its
linear algebra is small (3 x 3 covariances, a few thousand particles by three), far below what
a multi-threaded BLAS speeds up. NumPy's OpenBLAS nevertheless starts a thread per core when
NumPy is imported, and those threads spin while they wait for work: on a 2-core machine about
0.07 s of CPU right after the import and more after calls, measured with ``time`` on
``python -c "import numpy; import time; time.sleep(0.5)"`` (0.07 s of user time, 0.00 s with
one BLAS thread). A robot pays that on every core it shares with the planner.

So a symloc process asks for one BLAS thread unless its user asked for something else
(:func:`configure_process`, called by :func:`symloc.cli.main.main` before any command imports
NumPy). This module imports nothing heavy: it must run before NumPy is loaded to have an
effect. A program that imports symloc as a library keeps its own setting.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping

__all__ = ["PROCESS_ENV", "configure_process"]

#: Environment variables a symloc process sets when they are not set already.
PROCESS_ENV: Mapping[str, str] = {
    "OPENBLAS_NUM_THREADS": "1",  # NumPy's wheels (OpenBLAS)
    "MKL_NUM_THREADS": "1",  # NumPy built against MKL (conda)
}


def configure_process() -> bool:
    """Set :data:`PROCESS_ENV` in ``os.environ`` where the user has not set a value.

    Returns whether it can still take effect in this process (NumPy not imported yet); the
    variables are set either way, so the processes this one starts inherit them.
    """
    for key, value in PROCESS_ENV.items():
        os.environ.setdefault(key, value)
    return "numpy" not in sys.modules
