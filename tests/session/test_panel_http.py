"""The session's panel over real HTTP on loopback (a real `offline-prog session`, no
mocks): another web page, a rebinding name or a request without the printed token
cannot drive or read it (403/415, nothing changed); a bad value or body is a 400 with
one line and the session keeps running with its values."""

import time

import pytest

from live_session import Live, copy_cell, free_port_pair, start

CELL = "tape_cylinder_ur10e.yaml"
MOVED_MM = 1234.0  # a tool-stand x no test's legitimate request sets


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    """One session for the tests whose requests must all be refused (each checks that
    nothing changed); tests that change state start their own."""
    folder = tmp_path_factory.mktemp("session")
    session = start(folder, copy_cell(CELL, folder), free_port_pair())
    yield session
    session.stop()


@pytest.fixture
def own(tmp_path):
    """A session of this test's own (it changes the state)."""
    session = start(tmp_path, copy_cell(CELL, tmp_path), free_port_pair())
    yield session
    session.stop()


def unchanged(live: Live, before: dict) -> None:
    after = live.status()
    assert after["values"] == before["values"] and after["auto"] == before["auto"]
    assert after["generation"] == before["generation"]


def test_the_printed_url_carries_a_secret_token(live):
    assert live.url.startswith(f"http://localhost:{live.port}/?token=")
    assert len(live.token) >= 32
    code, text = live.send("GET", "/", headers={"X-Session-Token": None})
    assert code == 403 and "open the URL the session printed" in text
    code, text = live.send("GET", f"/?token={live.token}", headers={"X-Session-Token": None})
    assert code == 200 and "<title>offline_prog session</title>" in text
    # Its icon is inline: a browser asks no /favicon.ico, which would be refused
    # without the token (a 403 in the console on every load).
    assert '<link rel="icon" href="data:,">' in text


@pytest.mark.parametrize(
    ("headers", "expected"),
    [
        ({"Origin": "http://evil.example", "Content-Type": "text/plain"}, 403),
        ({"Origin": "http://evil.example"}, 403),  # even with the token
        ({"Origin": "null"}, 403),  # a sandboxed frame, a file:// page
        ({"Origin": "http://localhost:1"}, 403),  # another local server's page
        ({"Content-Type": "text/plain"}, 415),  # a browser sends it cross-site unasked
        ({"Content-Type": None}, 415),
        ({"X-Session-Token": None}, 403),
        ({"X-Session-Token": "guessed"}, 403),
    ],
)
def test_another_page_cannot_move_the_tool(live, headers, expected):
    before = live.status()
    code, reply = live.send("POST", "/set", {"key": "X_IT.x", "value": MOVED_MM}, headers=headers)
    assert code == expected and reply["ok"] is False, reply
    assert reply["message"].startswith("refused: ") and "\n" not in reply["message"]
    unchanged(live, before)


def test_another_page_cannot_save_or_export(live):
    before = live.status()
    for name in ("save", "export"):
        code, reply = live.send(
            "POST", "/action", {"name": name}, headers={"Origin": "http://evil.example"}
        )
        assert code == 403 and reply["ok"] is False, reply
    time.sleep(1.0)  # a Save would have been written by now
    assert sorted(p.name for p in live.folder.iterdir()) == ["data", CELL]
    after = live.status()
    assert after["saved"] is None and after["exported"] is None
    unchanged(live, before)


def test_a_rebinding_name_cannot_read_the_status(live):
    """DNS rebinding: evil.example resolves to 127.0.0.1; its page is same-origin with
    itself, its requests name evil.example as the Host."""
    for host in ("evil.example", f"evil.example:{live.port}", f"localhost:{live.port + 7}"):
        code, reply = live.send("GET", "/status", headers={"Origin": None}, host=host)
        assert code == 403 and "values" not in reply, reply
        assert reply["message"].startswith("refused: Host")
    for host in (f"localhost:{live.port}", f"127.0.0.1:{live.port}", f"LOCALHOST:{live.port}"):
        assert live.send("GET", "/status", host=host, headers={"Origin": None})[0] == 200


def test_bad_values_are_400_and_the_session_keeps_running_with_its_values(own):
    # What the panel page sends (its origin, the token, JSON) passes: an unsaved edit
    # the user would lose if the session died.
    code, reply = own.send("POST", "/set", {"key": "X_IT.x", "value": "1010"})
    assert code == 200 and reply == {"ok": True}
    for name, value in (("seek", 12.5), ("seek", "3"), ("pause", None), ("auto", "false")):
        code, reply = own.send("POST", "/action", {"name": name, "value": value})
        assert code == 200 and reply == {"ok": True}, (name, value, reply)
    assert own.status()["auto"] is False  # "false" is false
    before = own.status()
    deep = b"[" * 3000 + b"]" * 3000
    bad = [
        ("/action", {"name": "seek", "value": "nan"}, "σ 'nan' is not a finite number"),
        ("/action", {"name": "seek", "value": "-inf"}, "is not a finite number"),
        ("/action", b'{"name": "seek", "value": NaN}', "NaN is not a JSON number"),
        ("/action", {"name": "seek", "value": [1]}, "is not a number"),
        ("/action", {"name": "auto", "value": "no"}, "auto 'no' is not true or false"),
        ("/action", {"name": "auto", "value": 1}, "is not true or false"),
        ("/action", {"name": "auto"}, "is not true or false"),
        ("/action", {"name": "save", "value": "x"}, "save takes no value"),
        ("/action", {"name": "reboot"}, "no action 'reboot'"),
        ("/action", {"name": ["seek"]}, "action ['seek'] is not text"),
        ("/action", deep, "nested deeper than 2 levels"),
        ("/action", b'{"name": "pl', "not JSON"),
        ("/action", b"\xff\xfe", "not UTF-8"),
        ("/action", b" " * 20_000, "larger than 10000 bytes"),
        ("/set", {"key": "X_IT.x", "value": "nan"}, "is not a finite number"),
        ("/set", {"key": "X_IT.x", "value": True}, "is not a number or text"),
        ("/set", {"key": "X_IT.x", "value": {"a": 1}}, "is not a number or text"),
        ("/set", {"key": "speed", "value": "0"}, "must be > 0"),
        ("/set", {"key": "X_IT.x", "value": 5, "extra": 1}, "unexpected key 'extra'"),
        ("/set", [1, 2], "expected a JSON object"),
    ]
    for path, body, reason in bad:
        code, reply = own.send("POST", path, body)
        assert code == 400 and reply["ok"] is False, (body, reply)
        assert reason in reply["message"] and "\n" not in reply["message"], (body, reply)
    time.sleep(0.5)  # a few main-loop rounds: a NaN σ would have reached Drake
    assert own.process.poll() is None, own.stderr()
    after = own.status()
    assert after["values"]["X_IT.x"] == 1010.0 and after["auto"] is False
    assert after["values"] == before["values"]
    assert own.stop() == 130, own.stderr()[-2000:]
    stderr = own.stderr()
    assert "Traceback" not in stderr and "RecursionError" not in stderr, stderr


def test_a_touches_file_passes_the_same_guard(live):
    """POST /touches (the panel's calibration): another page, a missing token or a
    form body is refused before the session reads it; a bad file or a body beyond the
    touches limit is a 400 with one line; the session keeps its values."""
    before = live.status()
    body = {"file": "t.csv", "text": "target,q1_deg\n", "controller_angles": False}
    for headers, expected in (
        ({"Origin": "http://evil.example"}, 403),
        ({"X-Session-Token": None}, 403),
        ({"Content-Type": "text/plain"}, 415),
    ):
        code, reply = live.send("POST", "/touches", body, headers=headers)
        assert code == expected and reply["ok"] is False, (headers, reply)
    code, reply = live.send("POST", "/touches", body)
    assert code == 400 and "calibration: missing" in reply["message"], reply  # the tape demo
    code, reply = live.send("POST", "/touches", {**body, "path": "/etc/passwd"})
    assert code == 400 and "unexpected key 'path'" in reply["message"]
    code, reply = live.send("POST", "/touches", {**body, "text": "x" * 250_000})
    assert code == 400 and "larger than 200000 bytes" in reply["message"]
    unchanged(live, before)
    assert live.status()["calibration"] is None
