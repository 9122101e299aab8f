"""symloc.runtime: the environment a symloc process starts with."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from symloc.runtime import PROCESS_ENV, configure_process


def test_sets_one_blas_thread_where_unset(monkeypatch: pytest.MonkeyPatch) -> None:
    for key in PROCESS_ENV:
        monkeypatch.delenv(key, raising=False)
    # True only while NumPy is not loaded yet; set either way, for child processes
    assert configure_process() is ("numpy" not in sys.modules)
    assert os.environ["OPENBLAS_NUM_THREADS"] == "1"


def test_keeps_the_users_setting(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "4")
    configure_process()
    assert os.environ["OPENBLAS_NUM_THREADS"] == "4"


def test_runs_before_numpy_in_a_fresh_process() -> None:
    """The module and the command line's entry imports load no NumPy: the setting takes
    effect in the ``symloc`` process."""
    code = (
        "import sys, symloc.cli.main, symloc.runtime as r;"
        " print(r.configure_process(), 'numpy' in sys.modules)"
    )
    env = {k: v for k, v in os.environ.items() if k not in PROCESS_ENV}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    assert out.stdout.split() == ["True", "False"]


def test_the_command_line_configures_its_process() -> None:
    code = (
        "import os, contextlib, io; from symloc.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try: main(['--version'])\n"
        "    except SystemExit: pass\n"
        "print(os.environ.get('OPENBLAS_NUM_THREADS'))"
    )
    env = {k: v for k, v in os.environ.items() if k not in PROCESS_ENV}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "1"
