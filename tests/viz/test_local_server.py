"""Where `preview` (and `plan --preview`) listen: localhost unless --host says otherwise,
IPv6 loopback too; a privileged or taken port is one line and exit 2 before planning
(not Drake's abort, exit 1, or a bare RuntimeError, exit 3)."""

import signal
import socket
import subprocess
import sys

import pytest

from offline_prog.viz import local_server

from conftest import CELLS, REPO
from live_session import free_port_pair

CELL = str(CELLS / "tape_cylinder_ur10e.yaml")


def offline_prog(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "offline_prog", *args],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=timeout,
    )


@pytest.mark.parametrize(
    "command",
    [
        ["preview", CELL, "--port", "1"],
        ["preview", CELL, "--port", "1023"],
        ["plan", CELL, "--preview", "--port", "80", "--out"],
        ["session", CELL, "--port", "443", "--no-browser", "--seconds", "0"],
    ],
)
def test_a_privileged_port_is_one_line_exit_2(command, tmp_path):
    if command[-1] == "--out":
        command = [*command, str(tmp_path / "out")]
    done = offline_prog(*command)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert "--port" in lines[0] and ">= 1024" in lines[0]


def test_a_taken_port_is_one_line_exit_2_naming_it(tmp_path):
    with socket.socket() as taken:
        taken.bind(("localhost", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = offline_prog("preview", CELL, "--port", str(port), "--seconds", "0")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0] == (
        f"error: localhost:{port}: --port: cannot listen on port {port}: Address already in use"
    )
    assert done.stdout == ""  # refused before planning


def test_a_port_left_in_time_wait_is_free():
    """A server that closed a connection first leaves its port in TIME_WAIT; a new
    server (SO_REUSEADDR, as HTTPServer and MeshCat set it) may listen there at once."""
    with socket.socket() as server:
        server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        server.bind(("localhost", 0))
        server.listen()
        port = server.getsockname()[1]
        client = socket.create_connection(("localhost", port))
        accepted, _ = server.accept()
        accepted.close()  # the server's side closes first
        client.close()
    local_server.check_free("localhost", port)  # no InputError


def test_urls_name_the_host_as_a_browser_needs_it():
    url = local_server.url
    assert url("localhost", 7000) == "http://localhost:7000/"
    assert url("::1", 7000, "/?token=t") == "http://[::1]:7000/?token=t"
    assert url("0.0.0.0", 7000, "") == f"http://{socket.gethostname()}:7000"


def outward_address() -> str:
    """This machine's address on its default route (no packet is sent), or skip."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("198.51.100.1", 9))  # TEST-NET-2: only the route is looked up
        except OSError:
            pytest.skip("no network interface besides loopback")
        address = probe.getsockname()[0]
    if address.startswith("127."):
        pytest.skip("no network interface besides loopback")
    return address


def reachable(address: str, port: int) -> bool:
    try:
        with socket.create_connection((address, port), timeout=5):
            return True
    except OSError:
        return False


@pytest.mark.slow
@pytest.mark.parametrize("host", [None, "::1"])
def test_preview_listens_on_loopback_only(host):
    outward = outward_address()
    port = free_port_pair(host or "localhost")
    flags = ["--host", host] if host else []
    process = subprocess.Popen(
        [sys.executable, "-m", "offline_prog", "preview", CELL, "--port", str(port), *flags],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = process.stdout.readline()
        name = "[::1]" if host else "localhost"
        assert line.startswith(f"MeshCat preview at http://{name}:{port} "), process.stderr.read()
        assert reachable("::1" if host else "127.0.0.1", port)
        assert not reachable(outward, port)  # another machine could not reach it
    finally:
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=30) in (0, 130)  # 130 if it lands before the serving loop
