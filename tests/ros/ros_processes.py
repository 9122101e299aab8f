"""Helpers of the DDS tests that run ``symloc ros node`` as a child process."""

from __future__ import annotations

import signal
import subprocess


def stop_node(proc: subprocess.Popen[bytes] | subprocess.Popen[str], timeout: float = 10.0) -> None:
    """Stop a node as ``ros2 launch`` would: SIGINT, then SIGKILL after ``timeout`` [s]."""
    if proc.poll() is not None:
        return
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
