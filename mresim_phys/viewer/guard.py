"""Viewer (output edge), guard: which clients, ``Host`` names and ``Origin`` pages it answers.

Three checks run before any handler (``server.ViewerServer``'s middleware), each refusing
with 403 and a one-paragraph body:

* the client's address is this machine's loopback, unless ``--allow-remote``;
* the ``Host`` header names this viewer: its bound address with its port; when bound to
  loopback (or to every address), also ``localhost``, ``127.0.0.1`` and ``[::1]`` with the
  port, and the address the connection arrived at; and any name given with
  ``--allow-host NAME`` (any port) or ``--allow-host NAME:PORT``. This stops DNS
  rebinding: a page of another site whose name later resolves to 127.0.0.1 sends its own
  name as ``Host``;
* an ``Origin`` header, when present, names a page of this viewer (the same names as
  ``Host``, with ``http://``; ``https://`` only for an allowed name, e.g. a proxy's).
  Browsers send it with WebSocket upgrades and with every request that can change
  state; a client that sends none (curl, a script) is not a page of another site.

Typical use: ``Guard("127.0.0.1", ["viewer.lan"]).refusal(hosts, origins, where)``.
"""

from __future__ import annotations

import ipaddress
import re
from collections.abc import Iterable
from dataclasses import dataclass

LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")
EVERY_ADDRESS = ("0.0.0.0", "::", "")
DEFAULT_PORTS = {"http": 80, "https": 443}
HOST_PATTERN = re.compile(r"(?:\[([0-9A-Za-z:.%]+)\]|([0-9A-Za-z._-]+))(?::([0-9]{1,5}))?")
ORIGIN_PATTERN = re.compile(r"([a-z]+)://([^/?#@\s]+)")
SHOWN = 60  # characters of a refused header quoted back


def is_local(address: str | None) -> bool:
    """Whether a peer address is this machine's loopback (127.0.0.0/8, ::1)."""
    if not address:
        return False
    try:
        ip = ipaddress.ip_address(address.split("%")[0])
    except ValueError:
        return False
    if isinstance(ip, ipaddress.IPv6Address) and ip.ipv4_mapped is not None:
        ip = ip.ipv4_mapped
    return ip.is_loopback


def canonical(name: str) -> str:
    """A host name lower-cased, an IP address in its standard form (IPv4-mapped as IPv4)."""
    try:
        ip = ipaddress.ip_address(name.split("%")[0])
    except ValueError:
        return name.lower()
    if isinstance(ip, ipaddress.IPv6Address) and ip.ipv4_mapped is not None:
        ip = ip.ipv4_mapped
    return str(ip)


def split_host(value: str) -> tuple[str, int | None] | None:
    """``name``, ``name:port`` or ``[v6]:port`` as (canonical name, port or None); None if
    it is not one of these."""
    found = HOST_PATTERN.fullmatch(value)
    if found is None:
        return None
    port = None if found.group(3) is None else int(found.group(3))
    if port is not None and not 0 < port <= 65535:
        return None
    return canonical(found.group(1) or found.group(2)), port


@dataclass(frozen=True)
class Allowed:
    """A name given with ``--allow-host``: on any port (port None) or on that port."""

    name: str
    port: int | None = None

    @classmethod
    def parse(cls, text: str) -> Allowed:
        """``NAME``, ``NAME:PORT``, ``[V6]:PORT`` or a bare IPv6 address; ValueError if not."""
        if text.count(":") > 1 and not text.startswith("["):  # a bare IPv6 address
            text = f"[{text}]"
        parts = split_host(text)
        if parts is None or not parts[0]:
            raise ValueError(
                f"--allow-host {text!r}: give a host name or address, optionally with"
                " :PORT (viewer.lan, viewer.lan:8765, [fd00::5]:8765)"
            )
        return cls(*parts)


@dataclass(frozen=True)
class Where:
    """A connection: the client's address, the address and port it arrived at."""

    remote: str | None
    local: str | None
    port: int


class Guard:
    """The server's checks, for a server bound to ``host`` with names allowed by the user."""

    def __init__(self, host: str, allowed: Iterable[str] = (), allow_remote: bool = False) -> None:
        self.host, self.allow_remote = canonical(host), allow_remote
        self.allowed = [Allowed.parse(text) for text in allowed]
        loopback = is_local(self.host) or self.host in ("localhost", *EVERY_ADDRESS)
        own = [] if self.host in EVERY_ADDRESS else [self.host]
        self.names = frozenset(own + [canonical(n) for n in LOOPBACK_NAMES if loopback])

    def accepts(self, value: str, port: int, local: str | None, scheme: str = "http") -> bool:
        """Whether ``value`` (a ``Host`` header, or an ``Origin``'s host) names this viewer
        serving on ``port``; ``local`` is the address the connection arrived at. The
        viewer serves plain HTTP, so only an allowed name (a proxy's) may come as https."""
        parts = split_host(value)
        if parts is None:
            return False
        name, given = parts
        asked = DEFAULT_PORTS.get(scheme, 80) if given is None else given
        if any(a.name == name and a.port in (None, asked) for a in self.allowed):
            return True
        own = name in self.names or (local is not None and name == canonical(local))
        return own and asked == port and scheme == "http"

    def origin_accepted(self, origin: str, port: int, local: str | None) -> bool:
        """Whether an ``Origin`` header names a page of this viewer (``null`` does not)."""
        found = ORIGIN_PATTERN.fullmatch(origin.lower())
        if found is None or found.group(1) not in DEFAULT_PORTS:
            return False
        return self.accepts(found.group(2), port, local, found.group(1))

    def refusal(self, hosts: list[str], origins: list[str], where: Where) -> str | None:
        """Why a request is refused (the 403 body), or None if it is accepted.

        ``hosts`` and ``origins`` are every ``Host`` and ``Origin`` header it carries."""
        if not self.allow_remote and not is_local(where.remote):
            return "mresim viewer: only this machine may connect (start it with --allow-remote)."
        if len(hosts) > 1 or (hosts and not self.accepts(hosts[0], where.port, where.local)):
            return (
                f"mresim viewer: refused a request for host {shown(', '.join(hosts))}: this"
                " viewer answers only its own address (a page of another site may be reaching"
                " it through its own name). Start it with --allow-host NAME to accept a name."
            )
        if len(origins) > 1 or (
            origins and not self.origin_accepted(origins[0], where.port, where.local)
        ):
            return (
                "mresim viewer: refused a request from a page of another site"
                f" (Origin {shown(', '.join(origins))})."
            )
        return None


def shown(text: str) -> str:
    """``text`` quoted, cut to :data:`SHOWN` characters."""
    return repr(text if len(text) <= SHOWN else text[:SHOWN] + "...")
