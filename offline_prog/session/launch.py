"""Start a session: MeshCat and the panel on two ports, the URL and the SSH hint, the
main loop until Ctrl-C (or ``seconds``).

The panel is served on ``port`` and MeshCat on ``port + 1``, both on ``host``
(localhost by default: nothing is reachable from other machines unless asked; from
another machine, tunnel both ports over SSH).
"""

from __future__ import annotations

import os
import socket
import sys
import time
import webbrowser
from collections.abc import Callable
from pathlib import Path

from offline_prog.errors import InputError
from offline_prog.session.panel import serve_panel
from offline_prog.session.server import FRAME_S, Session

ANY_HOST = ("0.0.0.0", "*", "")


def _check_free(host: str, port: int) -> None:
    """InputError naming ``--port`` when the port cannot be bound on the host."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        try:
            probe.bind(("0.0.0.0" if host in ANY_HOST else host, port))
        except OSError as error:
            reason = f"cannot listen: {error.strerror} (the session uses this port and the next)"
            raise InputError(f"{host}:{port}", "--port", reason) from None


def _has_display() -> bool:
    """A desktop to open a browser on (never a text-mode browser in this terminal)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def run_session(
    cell_file: Path,
    *,
    host: str = "localhost",
    port: int = 7000,
    open_browser: bool = True,
    seconds: float | None = None,
    say: Callable[[str], None] = print,
) -> None:
    """Serve the session of ``cell_file`` until Ctrl-C (KeyboardInterrupt propagates
    after the servers stop) or ``seconds``.

    Raises:
        InputError: a bad cell file, or a port that is taken.
    """
    from pydrake.geometry import Meshcat, MeshcatParams

    meshcat_port = port + 1
    for p in (port, meshcat_port):
        _check_free(host, p)
    params = MeshcatParams()
    params.host, params.port = ("*" if host in ANY_HOST else host), meshcat_port
    params.show_stats_plot = False  # a realtime-rate plot means nothing here
    meshcat = Meshcat(params)
    session = Session(Path(cell_file), meshcat)
    server = serve_panel(session, "" if host in ANY_HOST else host, port, meshcat_port)
    shown = socket.gethostname() if host in ANY_HOST else host
    url = f"http://{shown}:{port}/"
    say(f"session of {cell_file} at {url} (MeshCat on port {meshcat_port}; Ctrl-C to stop)")
    say(
        f"from another machine: ssh -N -L {port}:localhost:{port} -L {meshcat_port}:"
        f"localhost:{meshcat_port} USER@{socket.gethostname()}, then open "
        f"http://localhost:{port}/"
    )
    if open_browser and _has_display():
        webbrowser.open(url)
    deadline = None if seconds is None else time.monotonic() + seconds
    try:
        while deadline is None or time.monotonic() < deadline:
            session.step()
            time.sleep(FRAME_S)
    finally:
        server.shutdown()
        server.server_close()
