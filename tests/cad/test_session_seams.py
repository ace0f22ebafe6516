"""The session links the part model's seams page: the same numbers as ``offline-prog
seams``, served by the panel's server beside the controls."""

import types
import urllib.request

from offline_prog.session.panel import page, seams_page_of, serve_panel

from conftest import CELLS


def test_the_panel_links_the_model_seams_page_of_a_cad_cell():
    cell = CELLS / "cad_seal_kr16.yaml"
    expected = seams_page_of(cell)
    assert b"<title>seams of seal_plate.step</title>" in expected
    assert seams_page_of(CELLS / "seal_plate_kr16.yaml") is None  # no part.model
    assert b'href="/seams"' in page(7001, seams=True)
    assert b"/seams" not in page(7001) and b"__SEAMS_LINK__" not in page(7001)
    session = types.SimpleNamespace(file=cell)  # the handler reads only the cell file here
    server = serve_panel(session, "127.0.0.1", 0, 7001)
    try:
        url = f"http://127.0.0.1:{server.server_address[1]}"
        with urllib.request.urlopen(f"{url}/") as answer:
            assert b'href="/seams"' in answer.read()
        with urllib.request.urlopen(f"{url}/seams") as answer:
            assert answer.status == 200 and answer.read() == expected
    finally:
        server.shutdown()
        server.server_close()
