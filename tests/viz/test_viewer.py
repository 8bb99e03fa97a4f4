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


class _ClientThatLosesTheViewer:
    """A ViewerClient whose viewer answers once and is gone when asked to open a file (the
    viewer without a Vulkan driver: it dies as it opens its window)."""

    @classmethod
    def connect(cls, url: str) -> _ClientThatLosesTheViewer:
        return cls()

    def get_state(self) -> object:
        return object()

    def open(self, path: str) -> None:
        raise ConnectionError("transport error")


@pytest.mark.skipif(os.name != "posix", reason="a shell script stands in for the viewer")
def test_a_viewer_that_dies_while_opening_the_file_is_a_viewer_error(tmp_path, monkeypatch):
    """The message says the viewer exited (the screenshot test skips on that outside CI) and
    why it may have: a fresh machine without Vulkan got a bare ConnectionError instead."""
    import rerun.experimental

    from surveil.viz import viewer

    fake = tmp_path / "rerun"
    fake.write_text("#!/bin/sh\nsleep 1\nexit 3\n")
    fake.chmod(0o755)
    monkeypatch.setattr(viewer, "rerun_executable", lambda: str(fake))
    monkeypatch.setattr(rerun.experimental, "ViewerClient", _ClientThatLosesTheViewer)
    with pytest.raises(viewer.ViewerError, match="exited with code 3 while opening .*Vulkan"):
        viewer.screenshot(tmp_path / "x.rrd", tmp_path / "x.png", timeout_s=10.0)
