"""A real `offline-prog session` in a subprocess, and real HTTP requests to it.

``start`` runs the command on a free port pair in a folder of the test's own, reads the
URL it prints (with its token) and returns a :class:`Live`; ``Live.send`` makes one
HTTP request on loopback with the headers the test chooses (by default those the
session's own page sends).
"""

from __future__ import annotations

import dataclasses
import http.client
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

import pytest

from conftest import CELLS, REPO

START_TIMEOUT_S = 60


def free_port_pair(host: str = "localhost") -> int:
    """A port p with p and p + 1 free on ``host`` (the panel and MeshCat)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    for _ in range(50):
        with socket.socket(family) as probe:
            probe.bind((host, 0))
            port = probe.getsockname()[1]
        if port < 65535:
            with socket.socket(family) as second:
                try:
                    second.bind((host, port + 1))
                    return port
                except OSError:
                    continue
    pytest.skip("no two free neighbouring ports")


@dataclasses.dataclass
class Live:
    """A running session: its process, address and the token its URL carries."""

    process: subprocess.Popen
    folder: Path
    host: str  # the address requests go to: 127.0.0.1 or ::1
    port: int
    url: str  # as printed
    token: str  # "" when the URL has none
    # What it wrote after the URL line, read as it comes (a terminal never blocks the
    # session; a pipe nobody reads would once 64 KiB were written): see ``stderr()``.
    printed: dict = dataclasses.field(default_factory=lambda: {"stdout": [], "stderr": []})
    readers: list = dataclasses.field(default_factory=list)

    def __post_init__(self):
        for name in ("stdout", "stderr"):
            reader = threading.Thread(
                target=_collect, args=(getattr(self.process, name), self.printed[name]), daemon=True
            )
            reader.start()
            self.readers.append(reader)

    def stderr(self) -> str:
        """What the session wrote on stderr so far (all of it once it ended)."""
        if self.process.poll() is not None:
            for reader in self.readers:
                reader.join(timeout=5)
        return "".join(self.printed["stderr"])

    def send(self, method: str, path: str, body=None, *, headers=None, host=None):
        """(status, JSON reply or text) of one request; ``body`` a dict or list (sent as JSON)
        or bytes. Headers default to the page's: Host, Origin, token, JSON."""
        name = f"[{self.host}]" if ":" in self.host else "localhost"
        sent = {
            "Host": host or f"{name}:{self.port}",
            "Origin": f"http://{name}:{self.port}",
            "X-Session-Token": self.token,
            "Content-Type": "application/json",
        }
        sent.update(headers or {})
        sent = {k: v for k, v in sent.items() if v is not None}
        data = json.dumps(body).encode() if isinstance(body, dict | list) else body
        connection = http.client.HTTPConnection(self.host, self.port, timeout=30)
        try:
            connection.request(method, path, body=data, headers=sent)
            reply = connection.getresponse()
            text = reply.read().decode()
        finally:
            connection.close()
        try:
            return reply.status, json.loads(text)
        except ValueError:
            return reply.status, text

    def status(self) -> dict:
        code, snapshot = self.send("GET", "/status")
        assert code == 200, snapshot
        return snapshot

    def stop(self) -> int:
        """Ctrl-C; the exit code (fails the test, with what the session wrote, if it
        does not stop)."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
        try:
            return self.process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.process.kill()
            code = self.process.wait()
            pytest.fail(
                f"the session did not stop on Ctrl-C within 30 s: {self.stderr()[-2000:]!r}"
            )
            return code


def _collect(stream, lines: list[str]) -> None:
    for line in stream:
        lines.append(line)


def copy_cell(name: str, folder: Path) -> Path:
    """The demo cell ``name`` copied into ``folder`` (its meshes linked beside it)."""
    shutil.copyfile(CELLS / name, folder / name)
    (folder / "data").symlink_to(CELLS / "data")
    return folder / name


def start(folder: Path, cell: Path, port: int, *, host: str | None = None) -> Live:
    """Run ``offline-prog session CELL --port PORT --no-browser [--host HOST]`` in
    ``folder``; returns once it printed its URL (fails the test with its stderr if not)."""
    flags = ["--host", host] if host else []
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "session",
            str(cell),
            "--port",
            str(port),
            "--no-browser",
            *flags,
        ],
        cwd=folder,
        env={**os.environ, "PYTHONPATH": str(REPO)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    line = process.stdout.readline()
    if " at http://" not in line:
        process.kill()
        pytest.fail(f"the session did not start: {line!r} {process.stderr.read()!r}")
    url = re.search(r" at (http://\S+)", line).group(1)
    token = (parse_qs(urlsplit(url).query).get("token") or [""])[0]
    address = "::1" if host == "::1" else "127.0.0.1"
    return Live(process, folder, address, port, url, token)
