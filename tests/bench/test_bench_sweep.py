"""run_sweep's process pool: a sweep killed from outside leaves no worker computing."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

SCRIPT = textwrap.dedent(
    """
    import os, sys, time
    from pathlib import Path
    from symloc.bench.sweep import run_sweep

    def task(i):
        Path(sys.argv[1], f"worker{i}.pid").write_text(str(os.getpid()))
        time.sleep(120)
        return i

    if __name__ == "__main__":
        run_sweep(task, [0, 1], workers=2)
    """
)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie is dead but still listed until its parent (here: init) reaps it
    stat = Path(f"/proc/{pid}/stat")
    return not (stat.is_file() and stat.read_text().split(")")[-1].split()[0] == "Z")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="parent-death signal is Linux's")
def test_killing_the_sweep_stops_its_workers(tmp_path: Path) -> None:
    script = tmp_path / "sweep.py"
    script.write_text(SCRIPT)
    proc = subprocess.Popen([sys.executable, str(script), str(tmp_path)])
    try:
        deadline = time.monotonic() + 60
        while len(list(tmp_path.glob("worker*.pid"))) < 2:
            assert time.monotonic() < deadline, "workers did not start"
            assert proc.poll() is None, "the sweep ended early"
            time.sleep(0.1)
        pids = [int(p.read_text()) for p in tmp_path.glob("worker*.pid")]
        assert all(_alive(pid) for pid in pids)
        proc.send_signal(signal.SIGKILL)  # no chance to shut its pool down
        proc.wait(timeout=10)
        deadline = time.monotonic() + 10
        while any(_alive(pid) for pid in pids) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not any(_alive(pid) for pid in pids), "orphaned workers kept running"
    finally:
        if proc.poll() is None:
            proc.kill()
        for p in tmp_path.glob("worker*.pid"):
            with contextlib.suppress(ProcessLookupError):
                os.kill(int(p.read_text()), signal.SIGKILL)
