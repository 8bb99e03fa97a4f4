"""Open, serve, verify and screenshot review recordings with the ``rerun`` viewer binary that
rerun-sdk installs beside the Python interpreter.

Headless screenshots need a Vulkan driver; on Debian the software one is
``mesa-vulkan-drivers`` + ``libvulkan1`` (``.ci/run`` installs them).
"""

from __future__ import annotations

import logging
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

log = logging.getLogger(__name__)


class ViewerError(RuntimeError):
    """The rerun viewer is missing, failed to start, or failed at its task."""


def rerun_executable() -> str:
    """Path of the ``rerun`` binary: beside the running Python first, then on PATH."""
    beside = Path(sys.executable).with_name("rerun")
    if beside.is_file():
        return str(beside)
    found = shutil.which("rerun")
    if found is None:
        raise ViewerError("the rerun viewer binary is not installed (pip install rerun-sdk)")
    return found


def display_available() -> bool:
    """True when a native viewer window can open (macOS, Windows, or X11/Wayland set)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def open_viewer(path: Path) -> subprocess.Popen:
    """Start the native viewer on ``path``, detached from this process."""
    return subprocess.Popen(
        [rerun_executable(), str(path)],
        start_new_session=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def serve_web(path: Path, *, port: int = 9090, bind: str = "127.0.0.1") -> int:
    """Serve ``path`` to a web viewer at ``http://{bind}:{port}`` until interrupted; returns
    the viewer's exit code."""
    cmd = [
        rerun_executable(),
        str(path),
        "--web-viewer",
        "--bind",
        bind,
        "--web-viewer-port",
        str(port),
    ]
    return subprocess.call(cmd)


def verify(path: Path) -> None:
    """``rerun rrd verify``: raise :class:`ViewerError` with its output if it rejects the file."""
    proc = subprocess.run(
        [rerun_executable(), "rrd", "verify", str(path)], capture_output=True, text=True
    )
    if proc.returncode != 0:
        raise ViewerError(f"rerun rrd verify {path} failed:\n{proc.stdout}{proc.stderr}")


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def screenshot(
    path: Path,
    png: Path,
    *,
    at_s: float | None = None,
    size: tuple[int, int] = (1600, 1000),
    timeout_s: float = 120.0,
    settle_s: float = 2.0,
) -> Path:
    """Render ``path`` in a headless viewer and save the window as ``png``.

    Parameters
    ----------
    path : an .rrd (or anything the viewer opens: an .mcap...)
    png : the image to write
    at_s : put the time cursor here (seconds on the ``time`` timeline); default: the end
    size : window size in logical points (the image is larger on HiDPI scale factors)
    timeout_s : give up after this long
    settle_s : let the viewer paint (and its start-up notifications fade) before the shot

    Raises
    ------
    ViewerError
        If the viewer cannot start (no Vulkan driver: install mesa-vulkan-drivers and
        libvulkan1) or does not write the image.
    """
    from rerun.experimental import ViewerClient

    path, png = Path(path).resolve(), Path(png).resolve()
    png.parent.mkdir(parents=True, exist_ok=True)
    png.unlink(missing_ok=True)
    port = _free_port()
    cmd = [
        rerun_executable(),
        "--headless",
        "--bind",
        "127.0.0.1",
        "--port",
        str(port),
        "--window-size",
        f"{size[0]}x{size[1]}",
        "--hide-welcome-screen",
    ]
    logfile = png.with_suffix(".viewer.log")
    with open(logfile, "w") as err:
        # its own process group: the ``rerun`` beside Python is a wrapper script that starts
        # the viewer binary as a child, which outlives the wrapper's terminate()
        proc = subprocess.Popen(
            cmd, stdout=err, stderr=subprocess.STDOUT, start_new_session=os.name == "posix"
        )
    try:
        client = _connect(ViewerClient, port, proc, timeout_s, logfile)
        try:
            client.open(str(path))
            deadline = time.monotonic() + timeout_s
            while client.get_state().loading:
                if time.monotonic() > deadline:
                    raise ViewerError(f"viewer still loading {path} after {timeout_s:.0f} s")
                time.sleep(0.2)
            if at_s is not None:
                client.set_time("time", duration=float(at_s), play_state="paused")
            else:
                client.set_time(play_state="following")
            time.sleep(settle_s)
            client.save_screenshot(str(png))
        except ConnectionError as exc:
            # without a Vulkan driver the viewer answers, then dies as it opens a window
            try:
                proc.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                raise ViewerError(f"lost the rerun viewer on port {port}: {exc}") from None
            raise _exited(proc, logfile, f"while opening {path}") from None
    finally:
        stop_process_group(proc)
    if not png.is_file():
        raise ViewerError(f"the viewer wrote no screenshot {png}; see {logfile}")
    logfile.unlink(missing_ok=True)
    return png


def stop_process_group(proc: subprocess.Popen, timeout_s: float = 10.0) -> None:
    """Terminate ``proc`` and, on POSIX, every process of its group (it must have been started
    with ``start_new_session=True``); kill them if ``proc`` outlasts ``timeout_s``."""

    def signal_all(sig: int) -> None:
        if os.name != "posix":
            proc.send_signal(sig)
            return
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:  # the whole group has exited already
            pass

    signal_all(signal.SIGTERM)
    try:
        proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        signal_all(signal.SIGKILL if os.name == "posix" else signal.SIGTERM)
        proc.wait()


def _exited(proc: subprocess.Popen, logfile: Path, when: str) -> ViewerError:
    """The error for a viewer process that has exited (``when``: what it was doing), with
    the end of its log."""
    tail = logfile.read_text(errors="replace")[-2000:]
    return ViewerError(
        f"the rerun viewer exited with code {proc.returncode} {when} (no Vulkan driver? on "
        f"Debian: apt-get install mesa-vulkan-drivers libvulkan1):\n{tail}"
    )


def _connect(client_cls, port: int, proc: subprocess.Popen, timeout_s: float, logfile: Path):
    """Wait until the headless viewer answers on ``port``."""
    deadline = time.monotonic() + timeout_s
    while True:
        if proc.poll() is not None:
            raise _exited(proc, logfile, "before answering")
        try:
            client = client_cls.connect(f"rerun+http://127.0.0.1:{port}/proxy")
            client.get_state()
            return client
        except Exception as exc:  # not up yet: the client raises whatever gRPC gives
            if time.monotonic() > deadline:
                raise ViewerError(
                    f"the rerun viewer did not answer on port {port}: {exc}"
                ) from None
            time.sleep(0.3)
