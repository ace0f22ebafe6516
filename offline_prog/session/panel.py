"""The session's panel: one HTML page beside the MeshCat viewer, and its JSON API.

MeshCat has sliders and buttons but no text, and a status line is the point of the
loop; so the panel is a small page of its own (stdlib HTTP server, no dependency):
the MeshCat viewer in a frame on the left (its own port, on the host the page came
from), the controls and the status line on the right. The API:

- ``GET /status``: :meth:`Session.snapshot` (the page polls it);
- ``POST /set`` ``{"key": ..., "value": "typed text"}``: a control's new value;
- ``POST /action`` ``{"name": "plan" | "save" | "export" | "play" | "pause" | "seek" |
  "auto", "value": ...}``;
- ``POST /touches`` ``{"file": name, "text": the touches file's text,
  "controller_angles": false}``: calibrate the cell from touches (``offline-prog
  calibrate``'s file; the panel reads it in the browser, so the session reads no path a
  page names) and draw the nominal and calibrated flange paths side by side;
- ``GET /seams``: for a cell with ``part.model``, the page of ``offline-prog seams`` on
  it (the model's faces, loops and chains with the numbers its ``cad:`` seams pick by),
  linked from the panel.

Every request passes the :mod:`~offline_prog.session.guard` checks first (403 if not:
Host, Origin, token; 415 for a POST that is not ``application/json``); a body or value
the session cannot use is 400 with a one-line ``message`` (:mod:`request`), and the
session keeps its values. An unexpected error is a 500 with one line, never a
traceback on the user's terminal.
"""

from __future__ import annotations

import contextlib
import json
import logging
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from urllib.parse import urlsplit

from offline_prog.session.guard import Guard, is_json
from offline_prog.session.request import (
    MAX_BODY_BYTES,
    MAX_TOUCHES_BODY_BYTES,
    RequestError,
    read_body,
)
from offline_prog.viz.local_server import bind_address, family

log = logging.getLogger(__name__)
PAGES = ("/", "/index.html")
KEYS = {  # what each POST takes
    "/set": ("key", "value"),
    "/action": ("name", "value"),
    "/touches": ("file", "text", "controller_angles"),
}
LIMITS = {"/touches": MAX_TOUCHES_BODY_BYTES}  # body sizes other than MAX_BODY_BYTES


SEAMS_LINK = (
    '<a id="seams" href="/seams" target="_blank" title="the part model\'s faces (F), loops '
    '(L) and edge chains (C) by the numbers offline-prog seams lists">model seams</a>'
)


def page(meshcat_port: int, *, seams: bool = False) -> bytes:
    """The panel page; with a link to the model's seams page when ``seams``."""
    text = (
        resources.files("offline_prog.session")
        .joinpath("assets/panel.html")
        .read_text(encoding="utf-8")
    )
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
    guard: Guard | None = None
    html = b""
    seams: bytes | None = None  # the model's seams page, made at start

    def log_message(self, format, *args):  # noqa: A002  (quiet: the terminal is the user's)
        pass

    def _send(self, status: int, body: bytes, kind: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("X-Frame-Options", "DENY")  # no other page frames the panel
        self.end_headers()
        self.wfile.write(body)

    def _json(self, value, status: int = HTTPStatus.OK) -> None:
        self._send(status, json.dumps(value).encode(), "application/json")

    def _refuse(self, status: int, message: str) -> None:
        self._json({"ok": False, "message": message}, status)

    def _checked(self) -> bool:
        """Host, Origin and token (see guard); False after a 403."""
        reason = self.guard.refusal(self.path, self.headers)
        if reason is not None and urlsplit(self.path).path in (*PAGES, "/seams"):  # a person
            self._send(HTTPStatus.FORBIDDEN, f"refused: {reason}\n".encode(), "text/plain")
        elif reason is not None:
            self._refuse(HTTPStatus.FORBIDDEN, f"refused: {reason}")
        return reason is None

    def do_GET(self) -> None:
        try:
            if not self._checked():
                return
            path = urlsplit(self.path).path
            if path in PAGES:
                self._send(HTTPStatus.OK, self.html, "text/html; charset=utf-8")
            elif path == "/status":
                self._json(self.session.snapshot())
            elif path == "/seams" and self.seams is not None:
                self._send(HTTPStatus.OK, self.seams, "text/html; charset=utf-8")
            else:
                self._refuse(HTTPStatus.NOT_FOUND, "not found")
        except Exception as error:  # one line to the page, never a traceback here
            self._failed(error)

    def do_POST(self) -> None:
        try:
            self._post()
        except Exception as error:
            self._failed(error)

    def _post(self) -> None:
        if not self._checked():
            return
        path = urlsplit(self.path).path
        if path not in KEYS:
            self._refuse(HTTPStatus.NOT_FOUND, "not found")
            return
        if not is_json(self.headers.get("Content-Type")):
            kind = self.headers.get("Content-Type")
            message = f"refused: Content-Type {kind!r}: the panel takes application/json"
            self._refuse(HTTPStatus.UNSUPPORTED_MEDIA_TYPE, message)
            return
        limit = LIMITS.get(path, MAX_BODY_BYTES)
        try:
            body = read_body(self._body(limit), keys=KEYS[path], max_bytes=limit)
        except RequestError as error:
            self._refuse(HTTPStatus.BAD_REQUEST, f"bad request: {error}")
            return
        if path == "/set":
            reply = self.session.set_value(body.get("key"), body.get("value"))
        elif path == "/touches":
            reply = self.session.load_touches(
                body.get("file"), body.get("text"), body.get("controller_angles", False)
            )
        else:
            reply = self.session.action(body.get("name"), body.get("value"))
        self._json(reply, HTTPStatus.OK if reply["ok"] else HTTPStatus.BAD_REQUEST)

    def _body(self, limit: int) -> bytes:
        """The body, at most ``limit`` bytes (RequestError otherwise; never read past)."""
        if self.headers.get("Transfer-Encoding") is not None:
            raise RequestError("send a Content-Length, not a Transfer-Encoding")
        try:
            length = int(self.headers.get("Content-Length") or 0)
        except ValueError:
            raise RequestError("Content-Length is not a number") from None
        if not 0 <= length <= limit:
            raise RequestError(f"body larger than {limit} bytes")
        return self.rfile.read(length)

    def _failed(self, error: Exception) -> None:
        log.exception("session panel request failed")
        with contextlib.suppress(OSError):  # the page went away
            self._refuse(HTTPStatus.INTERNAL_SERVER_ERROR, f"{type(error).__name__}: {error}")


def serve_panel(session, host: str, port: int, meshcat_port: int, *, guard: Guard):
    """Start the panel's server in a daemon thread; returns it (``shutdown()`` stops it).

    Args:
        host: ``--host`` (IPv6 literals too); guard: the checks every request passes.

    Raises:
        OSError: the port is taken or the host unknown.
    """
    seams = seams_page_of(session.file)
    html = page(meshcat_port, seams=seams is not None)
    attributes = {"session": session, "guard": guard, "html": html, "seams": seams}
    handler = type("Handler", (_Handler,), attributes)
    server_class = type(
        "PanelServer",
        (ThreadingHTTPServer,),
        {"address_family": family(host), "daemon_threads": True},
    )
    server = server_class((bind_address(host), port), handler)
    threading.Thread(target=server.serve_forever, name="session-panel", daemon=True).start()
    return server
