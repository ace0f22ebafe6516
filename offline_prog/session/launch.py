"""Start a session: MeshCat and the panel on two ports, the URL with its token and the
SSH hint, the main loop until Ctrl-C (or ``seconds``).

The panel is served on ``port`` and MeshCat on ``port + 1``, both on ``host``
(localhost by default: nothing is reachable from other machines unless asked; from
another machine, tunnel both ports over SSH). The panel answers only requests that
carry the session's token, from its own page and address (see ``guard``).
"""

from __future__ import annotations

import os
import socket
import sys
import time
import webbrowser
from collections.abc import Callable
from pathlib import Path

from offline_prog.session.guard import Guard, new_token
from offline_prog.session.panel import serve_panel
from offline_prog.session.server import FRAME_S, Session
from offline_prog.viz.local_server import check_free, open_meshcat, url

USES = "the session uses this port and the next"


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
    meshcat_port = port + 1
    check_free(host, port, uses=USES)
    meshcat = open_meshcat(host, meshcat_port, uses=USES)
    session = Session(Path(cell_file), meshcat)
    token = new_token()
    guard = Guard.serving(host, port, token)
    server = serve_panel(session, host, port, meshcat_port, guard=guard)
    address = url(host, port, f"/?token={token}")
    say(f"session of {cell_file} at {address} (MeshCat on port {meshcat_port}; Ctrl-C to stop)")
    say(
        f"from another machine: ssh -N -L {port}:localhost:{port} -L {meshcat_port}:"
        f"localhost:{meshcat_port} USER@{socket.gethostname()}, then open "
        f"http://localhost:{port}/?token={token}"
    )
    if open_browser and _has_display():
        webbrowser.open(address)
    deadline = None if seconds is None else time.monotonic() + seconds
    try:
        while deadline is None or time.monotonic() < deadline:
            session.step()
            time.sleep(FRAME_S)
    finally:
        server.shutdown()
        server.server_close()
