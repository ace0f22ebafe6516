"""The session links the part model's seams page: the same numbers as ``offline-prog
seams``, served by the panel's server beside the controls."""

import socket
import types
import urllib.error
import urllib.request

import pytest

from offline_prog.session.guard import Guard
from offline_prog.session.panel import page, seams_page_of, serve_panel

from conftest import CELLS


def test_the_panel_links_the_model_seams_page_of_a_cad_cell():
    cell = CELLS / "cad_seal_kr16.yaml"
    expected = seams_page_of(cell)
    assert b"<title>seams of seal_plate.step</title>" in expected
    assert seams_page_of(CELLS / "seal_plate_kr16.yaml") is None  # no part.model
    assert b'href="/seams"' in page(7001, seams=True)
    assert b'id="seams"' not in page(7001) and b"__SEAMS_LINK__" not in page(7001)
    session = types.SimpleNamespace(file=cell)  # the handler reads only the cell file here
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    guard = Guard.serving("127.0.0.1", port, "secret")
    server = serve_panel(session, "127.0.0.1", port, 7001, guard=guard)
    try:
        url = f"http://127.0.0.1:{port}"
        with urllib.request.urlopen(f"{url}/?token=secret") as answer:
            assert b'href="/seams"' in answer.read()
        with urllib.request.urlopen(f"{url}/seams?token=secret") as answer:
            assert answer.status == 200 and answer.read() == expected
        with pytest.raises(urllib.error.HTTPError, match="403"):  # the guard holds here too
            urllib.request.urlopen(f"{url}/seams")
    finally:
        server.shutdown()
        server.server_close()
