"""The session's panel: one HTML page beside the MeshCat viewer, and its JSON API.

MeshCat has sliders and buttons but no text, and a status line is the point of the
loop; so the panel is a small page of its own (stdlib HTTP server, no dependency):
the MeshCat viewer in a frame on the left (its own port, on the host the page came
from), the controls and the status line on the right. The API:

- ``GET /status``: :meth:`Session.snapshot` (the page polls it);
- ``POST /set`` ``{"key": ..., "value": "typed text"}``: a control's new value;
- ``POST /action`` ``{"name": "plan" | "save" | "export" | "play" | "pause" | "seek" |
  "auto", "value": ...}``;
- ``GET /seams``: for a cell with ``part.model``, the page of ``offline-prog seams`` on
  it (the model's faces, loops and chains with the numbers its ``cad:`` seams pick by),
  linked from the panel.
"""

from __future__ import annotations

import json
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources

MAX_BODY_BYTES = 10_000


SEAMS_LINK = (
    '<a id="seams" href="/seams" target="_blank" title="the part model\'s faces (F), loops '
    '(L) and edge chains (C) by the numbers offline-prog seams lists">model seams</a>'
)


def page(meshcat_port: int, *, seams: bool = False) -> bytes:
    """The panel page; with a link to the model's seams page when ``seams``."""
    text = resources.files("offline_prog.session").joinpath("assets/panel.html").read_text()
    text = text.replace("__SEAMS_LINK__", SEAMS_LINK if seams else "")
    return text.replace("__MESHCAT_PORT__", str(int(meshcat_port))).encode()


def seams_page_of(cell_file) -> bytes | None:
    """The seams page of the cell's ``part.model`` (None without one)."""
    from pathlib import Path

    from offline_prog.config.cell import load_cell
    from offline_prog.viz.seams_page import model_catalog, seams_html

    cell = load_cell(cell_file)
    if cell.part.model is None:
        return None
    model = Path(cell_file).parent / cell.part.model
    return seams_html(model_catalog(model, cell.part.mesh_units)).encode()


class _Handler(BaseHTTPRequestHandler):
    session = None  # set on the subclass made by serve_panel
    html = b""
    seams: bytes | None = None  # the model's seams page, made at start

    def log_message(self, format, *args):  # noqa: A002  (quiet: the terminal is the user's)
        pass

    def _send(self, status: int, body: bytes, kind: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def _json(self, value, status: int = HTTPStatus.OK) -> None:
        self._send(status, json.dumps(value).encode(), "application/json")

    def do_GET(self) -> None:
        path = self.path.split("?")[0]
        if path in ("/", "/index.html"):
            self._send(HTTPStatus.OK, self.html, "text/html; charset=utf-8")
        elif path == "/status":
            self._json(self.session.snapshot())
        elif path == "/seams" and self.seams is not None:
            self._send(HTTPStatus.OK, self.seams, "text/html; charset=utf-8")
        else:
            self._json({"ok": False, "message": "not found"}, HTTPStatus.NOT_FOUND)

    def do_POST(self) -> None:
        try:
            length = int(self.headers.get("Content-Length") or 0)
            if not 0 <= length <= MAX_BODY_BYTES:
                raise ValueError("request too large")
            body = json.loads(self.rfile.read(length) or b"{}")
            if not isinstance(body, dict):
                raise ValueError("expected a JSON object")
        except ValueError as error:
            self._json({"ok": False, "message": f"bad request: {error}"}, HTTPStatus.BAD_REQUEST)
            return
        if self.path == "/set":
            self._json(self.session.set_value(body.get("key"), body.get("value")))
        elif self.path == "/action":
            self._json(self.session.action(str(body.get("name")), body.get("value")))
        else:
            self._json({"ok": False, "message": "not found"}, HTTPStatus.NOT_FOUND)


def serve_panel(session, host: str, port: int, meshcat_port: int) -> ThreadingHTTPServer:
    """Start the panel's server in a daemon thread; returns it (``shutdown()`` stops it).

    Raises:
        OSError: the port is taken or the host unknown.
    """
    seams = seams_page_of(session.file)
    html = page(meshcat_port, seams=seams is not None)
    handler = type("Handler", (_Handler,), {"session": session, "html": html, "seams": seams})
    server = ThreadingHTTPServer((host, port), handler)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, name="session-panel", daemon=True).start()
    return server
