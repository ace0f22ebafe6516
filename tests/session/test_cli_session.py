"""``offline-prog session``: the URL with its token and the SSH hint, one-line errors
with exit 2 for a bad cell file or a taken port, a restart on the same port right after
Ctrl-C, IPv6 loopback."""

import re
import socket

import pytest

from offline_prog.cli import main

from conftest import CELLS
from live_session import copy_cell, free_port_pair, start


def test_session_prints_the_url_and_the_tunnel_hint(capsys):
    with socket.socket() as probe:
        probe.bind(("localhost", 0))
        port = probe.getsockname()[1]
    code = main(
        [
            "session",
            str(CELLS / "tape_cylinder_ur10e.yaml"),
            "--port",
            str(port),
            "--no-browser",
            "--seconds",
            "0",
        ]
    )
    out = capsys.readouterr().out
    assert code == 0, out
    token = re.search(rf"at http://localhost:{port}/\?token=([\w-]+) ", out).group(1)
    assert f"ssh -N -L {port}:localhost:{port} -L {port + 1}:localhost:{port + 1}" in out
    assert f"then open http://localhost:{port}/?token={token}" in out  # the same token


def test_a_taken_port_is_one_line_exit_2(capsys):
    with socket.socket() as taken:
        taken.bind(("localhost", 0))
        taken.listen()
        port = taken.getsockname()[1]
        code = main(
            [
                "session",
                str(CELLS / "tape_cylinder_ur10e.yaml"),
                "--port",
                str(port),
                "--no-browser",
                "--seconds",
                "0",
            ]
        )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--port" in err[0] and "cannot listen" in err[0]


def test_a_bad_cell_is_one_line_exit_2(capsys, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        (CELLS / "seal_plate_kr16.yaml").read_text().replace("speed: 0.1 ", "speed: -1 ")
    )
    code = main(["session", str(bad), "--port", "7390", "--no-browser", "--seconds", "0"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "motion.speed" in err[0], err


@pytest.mark.slow  # two session starts (CI runs the slow tests too)
def test_a_session_restarts_on_the_same_port_right_after_ctrl_c(tmp_path):
    cell = copy_cell("tape_cylinder_ur10e.yaml", tmp_path)
    port = free_port_pair()
    first = start(tmp_path, cell, port)
    first.status()  # the server closes this connection: its side of it waits in TIME_WAIT
    assert first.stop() == 130
    second = start(tmp_path, cell, port)  # at once, on the same port
    try:
        assert second.url.startswith(f"http://localhost:{port}/?token=")
        assert second.token != first.token  # a new session, a new secret
        assert second.status()["cell"] == str(cell)
    finally:
        assert second.stop() == 130


@pytest.mark.slow  # two session starts (CI runs the slow tests too)
def test_a_session_on_ipv6_loopback(tmp_path):
    try:
        port = free_port_pair("::1")
    except OSError:
        pytest.skip("no IPv6 loopback on this machine")
    live = start(tmp_path, copy_cell("tape_cylinder_ur10e.yaml", tmp_path), port, host="::1")
    try:
        assert live.url.startswith(f"http://[::1]:{port}/?token=")
        assert live.status()["cell"].endswith("tape_cylinder_ur10e.yaml")  # over IPv6
        with socket.create_connection(("::1", port + 1), timeout=10):
            pass  # MeshCat listens on ::1 too
    finally:
        assert live.stop() == 130
