"""The viewer refuses what a page of another site could send, and survives bad messages.

DNS rebinding: a page whose name later resolves to 127.0.0.1 sends its own name as
``Host`` (refused unless it names this viewer or ``--allow-host`` gave it); a page of
another site sends its own ``Origin`` (refused). Malformed WebSocket messages (deep,
big, binary, not JSON, NaN, wrong types) are answered with an error and change nothing.
"""

from __future__ import annotations

import socket
from collections.abc import Iterator
from pathlib import Path

import pytest
from conftest import write_scenario

from mresim_phys.cli import main
from mresim_phys.viewer.guard import Allowed, Guard, Where
from mresim_phys.viewer.replaysource import ReplaySource
from mresim_phys.viewer.server import ViewerServer

UPGRADE = (
    "Upgrade: websocket\r\nConnection: Upgrade\r\n"
    "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
)
FOREIGN_ORIGINS = ["http://evil.example", "null", "http://127.0.0.1:1", "file://", "ftp://x"]
PATHS = ["/", "/static/viewer.js", "/ws", "/nothing"]


@pytest.fixture(scope="module")
def source(tmp_path_factory: pytest.TempPathFactory) -> ReplaySource:
    """The replay of a 10-step run."""
    folder = tmp_path_factory.mktemp("security")
    out = folder / "run"
    path = write_scenario(folder, steps=10)
    assert main(["run", str(path), "--quiet", "--no-plots", "--out", str(out)]) == 0
    return ReplaySource.open(out)


def serving(source: ReplaySource, *allowed: str, host: str = "127.0.0.1") -> Iterator[int]:
    server = ViewerServer(source, host, 0, allow_hosts=allowed)
    server.start()
    try:
        yield server.port
    finally:
        server.close()


@pytest.fixture(scope="module")
def port(source: ReplaySource) -> Iterator[int]:
    yield from serving(source)


def ask(port: int, path: str, headers: str, method: str = "GET") -> tuple[int, str]:
    """Send one raw HTTP/1.1 request (``headers``: its header lines, Host included or not);
    its status and body (none for a WebSocket upgrade)."""
    with socket.create_connection(("127.0.0.1", port), timeout=10) as conn:
        conn.sendall(f"{method} {path} HTTP/1.1\r\n{headers}Connection: close\r\n\r\n".encode())
        data = b""
        while b"\r\n\r\n" not in data and (chunk := conn.recv(65536)):
            data += chunk
        status = int(data.split()[1])
        while status != 101 and (chunk := conn.recv(65536)):
            data += chunk
    return status, data.partition(b"\r\n\r\n")[2].decode("utf-8", "replace")


def upgrade_status(port: int, headers: str) -> int:
    return ask(port, "/ws", headers + UPGRADE)[0]


def test_a_foreign_host_is_refused_on_every_path(port: int) -> None:
    for host in ("evil.example", f"evil.example:{port}", f"127.0.0.1.evil.example:{port}"):
        for path in PATHS:
            status, body = ask(port, path, f"Host: {host}\r\n" + (UPGRADE if path == "/ws" else ""))
            assert status == 403, (host, path)
            assert "--allow-host" in body and "refused a request for host" in body
    assert ask(port, "/", f"Host: localhost:{port + 1}\r\n")[0] == 403  # not our port
    assert ask(port, "/", f"Host: localhost:{port}\r\nHost: evil.example\r\n")[0] in (400, 403)


def test_this_viewers_own_names_are_accepted(port: int) -> None:
    for host in (f"127.0.0.1:{port}", f"localhost:{port}", f"LocalHost:{port}", f"[::1]:{port}"):
        status, body = ask(port, "/", f"Host: {host}\r\n")
        assert status == 200 and "viewer.js" in body, host
        assert ask(port, "/static/viewer.js", f"Host: {host}\r\n")[0] == 200
        assert upgrade_status(port, f"Host: {host}\r\nOrigin: http://{host}\r\n") == 101


def test_a_foreign_origin_is_refused(port: int) -> None:
    host = f"Host: 127.0.0.1:{port}\r\n"
    for origin in [*FOREIGN_ORIGINS, f"http://evil.example:{port}", f"http://[::1]:{port + 1}"]:
        for path in PATHS:
            headers = host + f"Origin: {origin}\r\n" + (UPGRADE if path == "/ws" else "")
            status, body = ask(port, path, headers)
            assert status == 403 and "page of another site" in body, (origin, path)
        assert ask(port, "/", host + f"Origin: {origin}\r\n", method="POST")[0] == 403
    # a page of this viewer under another of its names is not another site
    assert upgrade_status(port, host + f"Origin: http://localhost:{port}\r\n") == 101


def test_clients_without_host_or_origin_are_served(port: int) -> None:
    """curl and scripts send no Origin; an HTTP/1.0 client may send no Host."""
    with socket.create_connection(("127.0.0.1", port), timeout=10) as conn:
        conn.sendall(b"GET / HTTP/1.0\r\n\r\n")
        assert conn.recv(100).startswith(b"HTTP/1.0 200")
    assert upgrade_status(port, f"Host: 127.0.0.1:{port}\r\n") == 101


def test_allow_host_accepts_the_names_given(source: ReplaySource) -> None:
    for port in serving(source, "viewer.lan", "proxy.lan:9000", "fd00::5"):
        for host in ("viewer.lan", "viewer.lan:443", "proxy.lan:9000", "[fd00::5]:80"):
            assert ask(port, "/", f"Host: {host}\r\n")[0] == 200, host
        for host in ("proxy.lan", "proxy.lan:9001", "other.lan", f"evil.viewer.lan:{port}"):
            assert ask(port, "/", f"Host: {host}\r\n")[0] == 403, host
        assert upgrade_status(port, "Host: viewer.lan\r\nOrigin: https://viewer.lan\r\n") == 101
        assert upgrade_status(port, "Host: viewer.lan\r\nOrigin: https://evil.lan\r\n") == 403


def test_a_server_on_every_address_answers_the_address_it_was_reached_at(
    source: ReplaySource,
) -> None:
    guard = Guard("0.0.0.0")
    assert guard.accepts("192.168.1.7:8765", 8765, "192.168.1.7")
    assert guard.accepts("localhost:8765", 8765, "127.0.0.1")
    assert not guard.accepts("192.168.1.8:8765", 8765, "192.168.1.7")
    assert not guard.accepts("evil.example:8765", 8765, "192.168.1.7")
    assert Guard("192.168.1.7").refusal(["localhost:8765"], [], Where("127.0.0.1", None, 8765))
    for port in serving(source, host="0.0.0.0"):
        assert ask(port, "/", f"Host: 127.0.0.1:{port}\r\n")[0] == 200
        assert ask(port, "/", f"Host: evil.example:{port}\r\n")[0] == 403


def test_a_malformed_allow_host_is_a_user_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for bad in ("http://x", "a b", "x:99999", ""):
        with pytest.raises(ValueError, match="--allow-host"):
            Allowed.parse(bad)
    run = write_scenario(tmp_path, steps=3)
    code = main(["run", str(run), "--view", "--port", "0", "--allow-host", "x/y"])
    err = capsys.readouterr().err
    assert code == 2 and "--allow-host 'x/y'" in err and len(err.strip().splitlines()) == 1
    code = main(["run", str(run), "--allow-host", "viewer.lan"])
    assert code == 2 and "--allow-host only applies with --view" in capsys.readouterr().err
