"""The viewer helpers leave no process behind."""

from __future__ import annotations

import os
import subprocess
import time
from pathlib import Path

import pytest

from surveil.viz.viewer import stop_process_group


def _alive(pid: int) -> bool:
    """Running (a zombie waiting for a reaper counts as gone)."""
    stat = Path(f"/proc/{pid}/stat")
    try:
        return stat.read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (FileNotFoundError, ProcessLookupError):
        return False


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs POSIX /proc")
def test_stopping_a_wrapper_stops_the_child_it_started():
    # like the ``rerun`` script beside Python: a wrapper that runs the real program as a child
    proc = subprocess.Popen(
        ["sh", "-c", "sleep 60 & echo $!; wait"],
        stdout=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    child = int(proc.stdout.readline())
    assert _alive(child)
    stop_process_group(proc, timeout_s=5.0)
    assert proc.returncode is not None
    deadline = time.monotonic() + 5.0  # the signal reaches the child asynchronously
    while _alive(child) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert not _alive(child)
    proc.stdout.close()


def test_stopping_an_exited_process_is_harmless():
    proc = subprocess.Popen(["true"], start_new_session=os.name == "posix")
    proc.wait()
    stop_process_group(proc, timeout_s=1.0)
    assert proc.returncode == 0
