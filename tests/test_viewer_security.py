"""The viewer refuses what a page of another site could send, and survives bad messages.

DNS rebinding: a page whose name later resolves to 127.0.0.1 sends its own name as
``Host`` (refused unless it names this viewer or ``--allow-host`` gave it); a page of
another site sends its own ``Origin`` (refused). Malformed WebSocket messages (deep,
big, binary, not JSON, NaN, wrong types) are answered with an error and change nothing.
"""

from __future__ import annotations

import asyncio
import json
import logging
import socket
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import aiohttp
import pytest
from conftest import write_scenario
from test_viewer_live import LAYERS, frames, next_frame, viewed_run

from mresim_phys.cli import main
from mresim_phys.viewer.guard import Allowed, Guard, Where
from mresim_phys.viewer.protocol import MAX_DEPTH, MAX_FRAME, MAX_MESSAGE, ProtocolError, decode
from mresim_phys.viewer.replaysource import ReplaySource
from mresim_phys.viewer.server import QUEUED_ERRORS, Page, ViewerServer

MakeScenario = Callable[..., Path]
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
    others = [f"http://evil.example:{port}", f"http://[::1]:{port + 1}", f"https://[::1]:{port}"]
    for origin in [*FOREIGN_ORIGINS, *others]:
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


def test_only_the_pages_own_files_are_served(port: int) -> None:
    host = f"Host: 127.0.0.1:{port}\r\n"
    for name in ("index.html", "viewer.js", "viewer.css"):
        assert ask(port, f"/static/{name}", host)[0] == 200
    for path in ("/static/" + "a" * 300, "/static/..%2fserver.py", "/static/", "/static/a/b"):
        assert ask(port, path, host)[0] == 404, path  # a name past 255 bytes was a 500


def test_a_request_aiohttp_cannot_parse_is_one_log_line(
    port: int, caplog: pytest.LogCaptureFixture
) -> None:
    """aiohttp logs a client's malformed request (400) as an error with a traceback: the
    viewer makes it an info line, so a stray request prints nothing by default."""
    with caplog.at_level(logging.INFO):
        assert ask(port, "/", "")[0] == 400  # HTTP/1.1 without a Host
    told = [r for r in caplog.records if "Missing 'Host'" in r.getMessage()]
    assert told and all(r.levelno == logging.INFO and not r.exc_info for r in told)


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


# --- messages -------------------------------------------------------------------------

DEEP = "[" * 100_000 + "]" * 100_000
BAD_MESSAGES: list[tuple[str | bytes, str]] = [
    (DEEP, "nests at most"),
    ("[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1), "nests at most"),
    ('{"op": "frame", "layers": {"team": ' + "[" * 50 + "]" * 50 + "}}", "nests at most"),
    ("x" * (MAX_MESSAGE + 1), "at most"),
    ("not json", "must be JSON"),
    ('{"op": "frame"', "must be JSON"),
    (b"\x00\x01binary", "not binary"),
    ('{"op": "speed", "value": NaN}', "NaN is not a JSON number"),
    ('{"op": "speed", "value": 1e400}', "too large"),
    ('{"op": "frame", "n": ' + "9" * 5000 + "}", "must be JSON"),
    ('{"op": "frame", "n": 1.5, "layers": {}}', "whole number"),
    ('{"op": "frame", "n": "1", "layers": {}}', "whole number"),
    ('{"op": "frame", "n": 0, "layers": {"robots": {"' + "Z" * 5000 + '": []}}}', "no agent"),
    ('{"op": "speed", "value": 1e9}', "speed must be"),
    ('{"op": "speed", "value": true}', "speed must be"),
    ('{"op": "launch"}', "needs 'op'"),
    ('{"op": ["play"]}', "needs 'op'"),
    ("[]", "needs 'op'"),
    ('"play"', "needs 'op'"),
    ("null", "needs 'op'"),
]


async def answers(port: int, messages: list[tuple[str | bytes, str]]) -> list[str]:
    """Each message's error reply; then check a good frame request is still answered."""
    replies = []
    url = f"ws://127.0.0.1:{port}/ws"
    async with aiohttp.ClientSession() as session, session.ws_connect(url) as ws:
        assert (await ws.receive_json(timeout=10))["type"] == "info"
        for message, _ in messages:
            await (ws.send_bytes if isinstance(message, bytes) else ws.send_str)(message)
            reply = await ws.receive_json(timeout=10)
            assert reply["type"] == "error"
            replies.append(str(reply["message"]))
        await ws.send_json({"op": "frame", "n": 3, "layers": LAYERS, "known": 0})
        assert (await next_frame(ws))["n"] == 3
    return replies


def test_malformed_messages_are_answered_and_the_viewer_goes_on(port: int) -> None:
    replies = asyncio.run(answers(port, BAD_MESSAGES))
    for (message, expected), reply in zip(BAD_MESSAGES, replies, strict=True):
        assert expected in reply, (str(message)[:80], reply)
        assert len(reply) < 300  # a message's contents are not echoed back whole


async def too_big(port: int) -> tuple[int | None, int]:
    """Send a message past the socket's limit: its close code, then a new page's frame."""
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(f"ws://127.0.0.1:{port}/ws") as ws:
            await ws.receive_json(timeout=10)
            await ws.send_str(" " * (MAX_FRAME + 1))
            while (await ws.receive(timeout=10)).type not in (
                aiohttp.WSMsgType.CLOSE,
                aiohttp.WSMsgType.CLOSED,
            ):
                pass
            code = ws.close_code
        async with session.ws_connect(f"ws://127.0.0.1:{port}/ws") as ws:
            await ws.receive_json(timeout=10)
            await ws.send_json({"op": "frame", "n": 5, "layers": LAYERS, "known": 0})
            return code, int((await next_frame(ws))["n"])


def test_a_message_past_the_limit_closes_only_its_socket(port: int) -> None:
    assert asyncio.run(too_big(port)) == (1009, 5)


def test_decode_bounds_the_message() -> None:
    assert decode('{"op": "frame", "layers": {"robots": {"A": ["path"]}}}')["op"] == "frame"
    assert decode('["[[[[[[[[[[[[[[[[[[[[", "\\"[[[[[[[[[[[[[["]') == [
        "[" * 20,
        '"' + "[" * 14,
    ]  # brackets inside strings do not count
    for bad in (DEEP, '{"a": -Infinity}', "[1e999]"):
        with pytest.raises(ProtocolError):
            decode(bad)


def test_a_page_that_never_reads_does_not_grow_its_queue(source: ReplaySource) -> None:
    server = ViewerServer(source, "127.0.0.1", 0)

    async def flood() -> int:
        page = Page(ws=None)  # type: ignore[arg-type]
        for _ in range(1000):
            server._refuse(page, "bad")
        return page.out.qsize()

    assert asyncio.run(flood()) == QUEUED_ERRORS


# --- a live run ---------------------------------------------------------------------------


async def refused_then_driven(url: str) -> dict[str, Any]:
    """Try to reach the run as a page of another site would, then drive it as a page of
    this viewer: bad messages first, then play to the end."""
    hostport = url.removeprefix("ws://").removesuffix("/ws")
    port = int(hostport.rsplit(":", 1)[1])
    foreign = [
        upgrade_status(
            port, f"Host: evil.example:{port}\r\nOrigin: http://evil.example:{port}\r\n"
        ),
        upgrade_status(port, f"Host: {hostport}\r\nOrigin: http://evil.example\r\n"),
    ]
    origin = {"Origin": f"http://{hostport}"}
    async with aiohttp.ClientSession() as session, session.ws_connect(url, headers=origin) as ws:
        assert (await ws.receive_json(timeout=30))["mode"] == "live"
        await ws.send_json({"op": "pause"})
        for message in (DEEP, '{"op": "speed", "value": NaN}', '{"op": "stop", "x": [[['):
            await ws.send_str(message)
            assert (await ws.receive_json(timeout=30))["type"] == "error"
        await ws.send_json({"op": "speed", "value": 1e-300})  # one step in 1e300 s
        await ws.send_json({"op": "play"})
        await asyncio.sleep(0.5)
        await ws.send_json({"op": "speed", "value": 0})  # applies at once
        last = await frames(ws, 1)
        while not last[0]["finished"]:
            last = await frames(ws, 1)
    return {"foreign": foreign, "last": last[0]}


def test_a_live_run_refuses_other_sites_and_survives_bad_messages(
    scenario_file: MakeScenario, tmp_path: Path
) -> None:
    path = scenario_file(steps=300, stop={"all_done": False, "stalled_for": None})
    out = tmp_path / "viewed"
    with viewed_run(path, out) as (url, child):
        started = time.monotonic()
        seen = asyncio.run(refused_then_driven(url))
        took = time.monotonic() - started
        assert child.poll() is None  # still serving the finished run
    assert seen["foreign"] == [403, 403]
    assert seen["last"]["step"] == 300 and took < 60
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stop_reason"] == "steps"  # no stop reached it
