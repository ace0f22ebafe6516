"""Who may drive a session: the panel's checks against other web pages and other hosts.

A browser lets any page it shows send requests to localhost, so without checks any web
page open beside the session could move the tool stand, or press Save and Export. The
panel refuses (403, nothing changed) a request that fails one of these, in this order,
as notebook servers do:

- Host: the ``Host`` header names the panel's own address (``localhost``,
  ``127.0.0.1``, ``[::1]`` or the ``--host`` given, with the panel's port). This stops
  DNS rebinding: a page of ``evil.example`` whose name later resolves to 127.0.0.1 is
  "same origin" with the panel for the browser, but its requests say
  ``Host: evil.example``. On every interface (``--host 0.0.0.0``), this machine's names
  and any IP address pass too (a rebinding needs a name, never an address);
- Origin: a browser names the page a request comes from; only the panel's own origin
  (an allowed host with the port) passes; no Origin (curl, scripts) passes;
- token: a per-session secret in the URL the session prints (``?token=...``); the
  page sends it with every request in the ``X-Session-Token`` header (a ``token``
  query parameter works too). A page that never saw the URL cannot know it.

POSTs must also say ``Content-Type: application/json`` (415 otherwise): a browser sends
a form or a ``text/plain`` body to another origin without asking; for JSON it asks
first (a CORS preflight), which the panel never grants.
"""

from __future__ import annotations

import dataclasses
import hmac
import ipaddress
import secrets
import socket
from urllib.parse import parse_qs, urlsplit

from offline_prog.viz.local_server import LOOPBACK_HOSTS, is_any

TOKEN_HEADER = "X-Session-Token"
TOKEN_BYTES = 24  # 192 random bits, URL-safe text


def new_token() -> str:
    """A fresh per-session secret."""
    return secrets.token_urlsafe(TOKEN_BYTES)


def _is_ip(name: str) -> bool:
    try:
        ipaddress.ip_address(name.strip("[]"))
    except ValueError:
        return False
    return True


@dataclasses.dataclass(frozen=True)
class Guard:
    """The panel's checks (see the module docstring).

    Attributes:
        token: the session's secret.
        port: the panel's port.
        names: the host names (lowercase; IPv6 in brackets) the panel answers to.
        any_ip: True on every interface: any IP address passes as a host too.
    """

    token: str
    port: int
    names: frozenset[str]
    any_ip: bool = False

    @classmethod
    def serving(cls, host: str, port: int, token: str) -> Guard:
        """The checks of a panel listening on ``host``:``port``."""
        names = {f"[{h}]" if ":" in h else h for h in (*LOOPBACK_HOSTS, host)}
        if is_any(host):
            names |= {socket.gethostname(), socket.getfqdn()}
        names = frozenset(n.lower() for n in names if n and not is_any(n))
        return cls(token, int(port), names, any_ip=is_any(host))

    def _allowed(self, host_port: str) -> bool:
        """True for ``name:port`` with a name the panel answers to and its port."""
        name, colon, port = host_port.strip().lower().rpartition(":")
        if not colon or port != str(self.port):
            return False
        return name in self.names or (self.any_ip and _is_ip(name))

    def refusal(self, path: str, headers) -> str | None:
        """Why a request is refused (one line), or None when it passes.

        Args:
            path: the request's path with its query (``/status?token=...``).
            headers: the request's headers (``email.message.Message``-like ``get``).
        """
        host = headers.get("Host")
        if host is None or not self._allowed(host):
            return f"Host {host!r} is not this session's address (localhost:{self.port})"
        origin = headers.get("Origin")
        if origin is not None:
            parts = urlsplit(origin)
            if parts.scheme != "http" or parts.path or not self._allowed(parts.netloc):
                return f"requests from the page {origin[:80]!r} are not accepted"
        token = headers.get(TOKEN_HEADER)
        if token is None:
            token = (parse_qs(urlsplit(path).query).get("token") or [""])[0]
        if not hmac.compare_digest(token.encode(), self.token.encode()):
            return "no or wrong session token: open the URL the session printed (?token=...)"
        return None


def is_json(content_type: str | None) -> bool:
    """True for ``application/json`` (parameters such as a charset allowed)."""
    return (content_type or "").split(";")[0].strip().lower() == "application/json"
