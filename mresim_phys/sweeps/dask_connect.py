"""Joining a Dask scheduler (sweeps, running): ``--dask tcp://host:8786``, bounded in time.

``distributed.Client(address, timeout=...)`` is not enough against something that is not
a Dask scheduler: a silent listener or an HTTP server (the Dask dashboard, say) keeps it
waiting for minutes, and a server that answers with text makes it read the text as a
message length (an exabyte allocation). So a ``tcp://`` address is probed first with a
plain socket: a Dask scheduler greets a new connection at once with a small framed
message (an 8-byte little-endian length, then the frames), which must arrive within
:data:`CONNECT_TIMEOUT` seconds and give a plausible length. Only then does the client
connect (also bounded; any failure of it is reported, never a traceback). Every failure is
one message naming the address (exit status 2).
"""

from __future__ import annotations

import socket
import struct
from typing import Any
from urllib.parse import urlsplit

from mresim_phys.errors import MresimError

CONNECT_TIMEOUT = 3.0  # seconds to reach a Dask scheduler and hear its greeting
GREETING_MAX = 1 << 20  # a scheduler's handshake is a few hundred bytes
ADVICE = (
    " Start one (`dask scheduler`, then `dask worker ADDRESS` on each machine) and give the"
    " address it prints (tcp://host:8786 by default; not the dashboard's :8787), or use"
    " --dask local:N or --workers N to run on this machine."
)


class NoScheduler(MresimError):
    """No Dask scheduler at the address given."""


def refuse(address: str, what: str) -> NoScheduler:
    """The one-paragraph message for ``--dask address`` where no scheduler answers."""
    return NoScheduler(f"--dask {address}: no Dask scheduler answered: {what}.{ADVICE}")


def malformed(address: str, what: str) -> NoScheduler:
    """The one-paragraph message for a ``--dask`` address of the wrong form."""
    return NoScheduler(f"--dask {address!r}: {what}.{ADVICE}")


def host_port(address: str) -> tuple[str, int]:
    """Host and port of a ``tcp://host:port`` address; NoScheduler if malformed."""
    try:
        parts = urlsplit(address)
        host, port = parts.hostname, parts.port
    except ValueError:
        host, port = None, None
    if not host or port is None:
        raise malformed(address, "expected tcp://HOST:PORT, e.g. tcp://127.0.0.1:8786")
    return host, port


def probe(address: str, timeout: float) -> None:
    """NoScheduler unless a Dask scheduler greets at ``address`` (tcp://) within
    ``timeout`` seconds."""
    host, port = host_port(address)
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            sock.settimeout(timeout)
            head = read_exactly(sock, 8)
    except TimeoutError:
        raise refuse(
            address,
            f"something accepts connections there but sent no Dask greeting within"
            f" {timeout:g} s (a silent listener, or an HTTP server such as the Dask dashboard?"
            " a Dask scheduler greets at once)",
        ) from None
    except OSError as exc:
        why = f"{type(exc).__name__}: {exc.strerror or exc}"
        raise refuse(address, f"cannot connect to {host}:{port} ({why})") from None
    (length,) = struct.unpack("<Q", head) if len(head) == 8 else (0,)
    if not 0 < length <= GREETING_MAX:
        raise refuse(
            address,
            f"the server there is not a Dask scheduler (it answered {head!r}, not a Dask greeting)",
        )


def read_exactly(sock: socket.socket, size: int) -> bytes:
    """Up to ``size`` bytes from ``sock`` (fewer if it closes first)."""
    data = b""
    while len(data) < size:
        chunk = sock.recv(size - len(data))
        if not chunk:
            break
        data += chunk
    return data


def connect(client_class: Any, address: str, timeout: float | None = None) -> Any:
    """A client of the scheduler at ``address``; NoScheduler if there is none within
    ``timeout`` seconds (default CONNECT_TIMEOUT)."""
    timeout = CONNECT_TIMEOUT if timeout is None else timeout
    if "://" not in address:
        raise malformed(
            address,
            "expected a scheduler address such as tcp://host:8786, or local:N to start a"
            " local cluster of N workers",
        )
    if address.startswith("tcp://"):
        probe(address, timeout)
    try:
        return client_class(address, timeout=timeout)
    except Exception as exc:  # any failure of a client we cannot vouch for is the address's
        detail = " ".join(str(exc).split())[:200]
        raise refuse(
            address, f"none within {timeout:g} s ({type(exc).__name__}: {detail})"
        ) from None
