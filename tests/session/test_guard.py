"""The panel's checks and request reading as functions: which Host and Origin pass for
each --host, the token from a header or the query, and JSON depth read without
recursion (brackets inside strings do not count)."""

import socket

import pytest

from offline_prog.session.guard import Guard, is_json
from offline_prog.session.request import RequestError, boolean, finite, read_body

TOKEN = "s3cret-token"


def ask(guard: Guard, host=None, origin=None, token=TOKEN, path="/status"):
    headers = {"Host": host or f"localhost:{guard.port}"}
    if origin is not None:
        headers["Origin"] = origin
    if token is not None:
        headers["X-Session-Token"] = token
    return guard.refusal(path, headers)


def test_on_localhost_only_the_loopback_names_with_the_port_pass():
    guard = Guard.serving("localhost", 7000, TOKEN)
    for host in ("localhost:7000", "127.0.0.1:7000", "[::1]:7000", "LocalHost:7000"):
        assert ask(guard, host=host) is None, host
    for host in (
        "evil.example:7000",
        "localhost:7001",
        "localhost",
        "192.0.2.2:7000",
        f"{socket.gethostname()}:7000",
        "127.0.0.1.evil.example:7000",
    ):
        assert ask(guard, host=host).startswith("Host "), host


def test_on_every_interface_this_machine_s_names_and_addresses_pass():
    guard = Guard.serving("0.0.0.0", 7000, TOKEN)
    for host in (f"{socket.gethostname()}:7000", "192.0.2.2:7000", "[fd00::2]:7000"):
        assert ask(guard, host=host) is None, host
    assert ask(guard, host="evil.example:7000").startswith("Host ")  # a rebinding name


def test_ipv6_loopback_and_a_named_host():
    assert ask(Guard.serving("::1", 7000, TOKEN), host="[::1]:7000") is None
    named = Guard.serving("cell-pc.local", 7000, TOKEN)
    assert ask(named, host="cell-pc.local:7000") is None
    assert ask(named, host="other.local:7000") is not None


@pytest.mark.parametrize(
    ("origin", "passes"),
    [
        ("http://localhost:7000", True),
        ("http://127.0.0.1:7000", True),
        ("http://evil.example", False),
        ("http://localhost:7001", False),  # MeshCat's page is another origin
        ("https://localhost:7000", False),
        ("null", False),
        ("http://localhost:7000/x", False),
    ],
)
def test_only_the_panel_s_own_origin_passes(origin, passes):
    reason = ask(Guard.serving("localhost", 7000, TOKEN), origin=origin)
    assert (reason is None) == passes, reason


def test_the_token_from_the_header_or_the_query():
    guard = Guard.serving("localhost", 7000, TOKEN)
    assert ask(guard, token=None, path=f"/?token={TOKEN}") is None
    assert "token" in ask(guard, token=None, path="/")
    assert "token" in ask(guard, token="s3cret-tokem")
    assert "token" in ask(guard, token="é")  # not ASCII: refused, not an error


def test_json_content_types():
    assert is_json("application/json") and is_json("Application/JSON; charset=utf-8")
    assert not is_json("text/plain") and not is_json(None) and not is_json("application/jsonx")


def test_brackets_in_strings_are_not_nesting():
    body = read_body(b'{"key": "[[[{{\\"[[", "value": "]]}"}', keys=("key", "value"))
    assert body == {"key": '[[[{{"[[', "value": "]]}"}
    with pytest.raises(RequestError, match="nested deeper than 2 levels"):
        read_body(b'{"key": [[1]]}', keys=("key",))


def test_values():
    assert finite("12.5", "σ") == 12.5 and finite(3, "σ") == 3.0
    for bad in ("nan", "inf", "1e999", True, None, [1], "12 mm"):
        with pytest.raises(RequestError):
            finite(bad, "σ")
    assert boolean("false", "auto") is False and boolean(True, "auto") is True
    for bad in ("False", "0", 0, 1, None, "yes", ""):
        with pytest.raises(RequestError):
            boolean(bad, "auto")
