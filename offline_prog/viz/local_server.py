"""Where the local servers listen: the host's forms, the free-port probe, the URL, and a
MeshCat bound to the host.

``preview``, ``plan --preview`` and ``session`` listen on localhost unless ``--host``
says otherwise (``0.0.0.0``: every interface; ``::1``: IPv6 loopback). A port is probed
before Drake's MeshCat is made, because MeshCat ends the process (a C++ abort, exit 1)
on a privileged port and raises a bare RuntimeError on a taken one; the probe names the
port and the flag instead (one line, exit 2).
"""

from __future__ import annotations

import errno
import socket

from offline_prog.errors import InputError

ANY_HOSTS = ("0.0.0.0", "::", "*", "")  # every interface
LOOPBACK_HOSTS = ("localhost", "127.0.0.1", "::1")
MIN_PORT = 1024  # Drake's MeshCat aborts below this (privileged ports)
MAX_PORT = 65535


def is_any(host: str) -> bool:
    """True when ``host`` means every interface."""
    return host in ANY_HOSTS


def family(host: str) -> socket.AddressFamily:
    """IPv6 for an IPv6 literal (``::1``, ``::``), IPv4 otherwise (names resolve so)."""
    return socket.AF_INET6 if ":" in host else socket.AF_INET


def bind_address(host: str) -> str:
    """The address a Python socket binds for ``host`` (``""``: every IPv4 interface)."""
    return "" if host in ("0.0.0.0", "*", "") else host


def url_host(host: str) -> str:
    """``host`` as a URL writes it: IPv6 in brackets, every interface as this machine's
    name (the address another machine would use)."""
    if is_any(host):
        return socket.gethostname()
    return f"[{host}]" if ":" in host else host


def url(host: str, port: int, path: str = "/") -> str:
    """``http://host:port/path`` for a server listening on ``host``."""
    return f"http://{url_host(host)}:{int(port)}{path}"


def check_free(host: str, port: int, *, uses: str = "") -> None:
    """Refuse (InputError naming ``--port`` or ``--host``) a port the servers could not
    listen on.

    The probe sets ``SO_REUSEADDR`` as the servers themselves do (Python's HTTPServer,
    uWebSockets under MeshCat), so a port that a server stopped a moment ago left in
    TIME_WAIT counts as free, as it is for them.

    Args:
        host: the ``--host`` value; port: the port [1024, 65535].
        uses: appended to the reason (e.g. "the session uses this port and the next").
    """
    where = f"{url_host(host)}:{port}"
    if not MIN_PORT <= port <= MAX_PORT:
        reason = f"{port} is not a port a server may use here ({MIN_PORT} to {MAX_PORT})"
        raise InputError(where, "--port", reason)
    with socket.socket(family(host), socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind((bind_address(host), port))
        except socket.gaierror as error:
            raise InputError(host, "--host", f"cannot resolve it: {error.strerror}") from None
        except OSError as error:
            if error.errno == errno.EADDRNOTAVAIL:
                raise InputError(host, "--host", "not an address of this machine") from None
            reason = f"cannot listen on port {port}: {error.strerror}"
            raise InputError(where, "--port", f"{reason} ({uses})" if uses else reason) from None


def open_meshcat(host: str, port: int, *, uses: str = ""):
    """Drake's MeshCat listening on ``host``:``port`` (checked first, see check_free).

    Returns:
        pydrake.geometry.Meshcat, without the realtime-rate plot (meaningless here).

    Raises:
        InputError: the port is taken or privileged, or the host is not this machine's.
    """
    from pydrake.geometry import Meshcat, MeshcatParams

    check_free(host, port, uses=uses)
    params = MeshcatParams()
    params.host, params.port = ("*" if is_any(host) else host), port
    params.show_stats_plot = False
    return Meshcat(params)
