"""``offline-prog session``: the URL and the SSH hint, one-line errors with exit 2 for a
bad cell file or a taken port."""

import socket

from offline_prog.cli import main

from conftest import CELLS


def test_session_prints_the_url_and_the_tunnel_hint(capsys):
    with socket.socket() as probe:
        probe.bind(("localhost", 0))
        port = probe.getsockname()[1]
    code = main(["session", str(CELLS / "tape_cylinder_ur10e.yaml"), "--port", str(port),
                 "--no-browser", "--seconds", "0"])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0, out
    assert f"at http://localhost:{port}/" in out
    assert f"ssh -N -L {port}:localhost:{port} -L {port + 1}:localhost:{port + 1}" in out


def test_a_taken_port_is_one_line_exit_2(capsys):
    with socket.socket() as taken:
        taken.bind(("localhost", 0))
        taken.listen()
        port = taken.getsockname()[1]
        code = main(["session", str(CELLS / "tape_cylinder_ur10e.yaml"), "--port", str(port),
                     "--no-browser", "--seconds", "0"])  # fmt: skip
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
