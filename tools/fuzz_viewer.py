"""Fuzz the viewer's server: random HTTP requests and WebSocket messages at a live server.

The server (``mresim_phys.viewer.server``) serves the replay of a small run on loopback
only, from its own thread, as ``mresim view`` does. Hypothesis draws each case: either
one HTTP request (method, path, ``Host``, ``Origin``, other headers, body; sometimes a
WebSocket upgrade, sometimes bytes that are no HTTP at all) sent over a raw socket, or
one WebSocket session from a page of the viewer's own (1 to 4 messages: valid requests
with odd values, random JSON, deep nesting, big and binary messages, NaN), closed by a
frame request that must be answered. The server must never answer 5xx, never log an
error, never stop, stay responsive (a page every 25 cases), and refuse (403) every
request whose ``Host`` or ``Origin`` does not name it.

    python tools/fuzz_viewer.py [--count 1000] [--seed 0] [--show 5]

prints the counts (requests by status, messages by reply, failures) and the first
failures. ``tests/test_fuzz_viewer.py`` runs a few hundred cases in the suite.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import logging
import shutil
import socket
import sys
import tempfile
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import aiohttp
import yaml
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the scenario fuzzer's runner
from fuzz_scenarios import run_cases

ROOT = Path(__file__).resolve().parent.parent
MAP = ROOT / "maps" / "small_rooms.png"  # 160x120, four rooms and a hall
TIMEOUT = 10.0  # seconds any answer may take
CHECK_EVERY = 25  # cases between two checks that the page is still served
SCENARIO: dict[str, Any] = {
    "name": "fuzz-viewer",
    "seed": 1,
    "steps": 12,
    "map": {"image": MAP.name, "resolution": 0.1},
    "base_station": {"position": [20, 60], "comm_range": 40},
    "team": {"speed": 3, "radius": 2, "sensor": {"range": 60}, "comm_range": 40},
    "robots": [{"name": "A", "start": [66, 52]}, {"name": "B", "start": [66, 68]}],
    "events": [{"step": 5, "fail": "B"}],
}

# --- HTTP requests ----------------------------------------------------------------------------

METHODS = ["GET", "GET", "GET", "HEAD", "POST", "PUT", "DELETE", "OPTIONS", "PATCH", "TRACE"]
PATHS = ["/", "/ws", "/static/viewer.js", "/static/viewer.css", "/static/index.html"]
PATHS += ["/static/", "/static/../server.py", "/static/%2e%2e/server.py", "/static/..%2f..%2f"]
PATHS += ["//", "/?x=1", "/index.html", "/static/viewer.js?v=1", "/%00", "/static/%00", "/ws/"]
PATHS += ["/static/" + "a" * 300, "/" + "b/" * 2000, "/static/%ff%fe", "/static/.", "/.git"]
URL_CHARS = st.text("abcdefghijklmnopqrstuvwxyz0123456789-._~/%?=&+;:@!$'()*,", max_size=40)
TOKEN = st.text("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-", min_size=1)
HEADER_TEXT = st.text(st.characters(min_codepoint=32, max_codepoint=126), max_size=60)
FOREIGN_NAMES = ["evil.example", "127.0.0.1.evil.example", "localhost.evil", "viewer", "0.0.0.0"]
UPGRADE = {
    "Upgrade": "websocket",
    "Connection": "Upgrade",
    "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==",
    "Sec-WebSocket-Version": "13",
}
EXTRA: list[dict[str, str]] = [
    {"Range": "bytes=0-10"},
    {"Range": "bytes=99999999-"},
    {"If-None-Match": "*"},
    {"If-Modified-Since": "not a date"},
    {"Accept-Encoding": "gzip, br"},
    {"Cookie": "a=b; " * 50},
    {"X-Forwarded-Host": "evil.example"},
    {"Referer": "http://evil.example/"},
    {"Sec-WebSocket-Version": "99"},
    {"X-Long": "x" * 6000},
]


@dataclass(frozen=True)
class Request:
    """One HTTP request: its bytes, whether its Host or Origin is another site's, whether
    it has no Host (aiohttp refuses that before any handler: 400)."""

    data: bytes
    foreign: bool = False
    hostless: bool = False


def names_of(port: int) -> tuple[list[str], list[str]]:
    """(this viewer's Host values, other sites' Host values) for a server on ``port``."""
    own = [f"127.0.0.1:{port}", f"localhost:{port}", f"[::1]:{port}", f"LOCALHOST:{port}"]
    foreign = [f"{n}:{port}" for n in FOREIGN_NAMES] + FOREIGN_NAMES
    foreign += [f"127.0.0.1:{port + 1}", f"localhost:{(port + 7) % 65536}", "127.0.0.1"]
    return own, foreign


@st.composite
def requests(draw: Callable[..., Any], port: int) -> Request:
    """A well-formed HTTP/1.1 request; its Host and Origin are this viewer's, absent or
    another site's."""
    own, foreign_hosts = names_of(port)
    method = draw(st.sampled_from(METHODS))
    path = draw(st.one_of(st.sampled_from(PATHS), URL_CHARS.map(lambda p: "/" + p)))
    host_kind = draw(st.sampled_from(["own", "own", "own", "none", "foreign"]))
    host = {"own": draw(st.sampled_from(own)), "none": None}.get(host_kind)
    if host_kind == "foreign":
        host = draw(st.one_of(st.sampled_from(foreign_hosts), TOKEN))
    origin_kind = draw(st.sampled_from(["none", "none", "own", "foreign"]))
    origin = {"own": "http://" + draw(st.sampled_from(own)), "none": None}.get(origin_kind)
    if origin_kind == "foreign":
        others = ["null", "http://evil.example", "https://" + own[0], "file://", "http://"]
        origin = draw(st.one_of(st.sampled_from(others + ["http://" + h for h in foreign_hosts])))
    upgrade = draw(st.booleans()) if path == "/ws" else draw(st.integers(0, 9)) == 0
    headers = {**(UPGRADE if upgrade else {"Connection": "close"})}
    for extra in draw(st.lists(st.sampled_from(EXTRA), max_size=3)):
        headers.update(extra)
    if draw(st.booleans()):
        headers[draw(TOKEN)] = draw(HEADER_TEXT)
    body = draw(st.binary(max_size=2000)) if draw(st.integers(0, 3)) == 0 else b""
    if body:
        headers["Content-Length"] = str(len(body))
    lines = [f"{method} {path} HTTP/1.1"]
    lines += [f"Host: {host}"] if host is not None else []
    lines += [f"Origin: {origin}"] if origin is not None else []
    lines += [f"{k}: {v}" for k, v in headers.items()]
    data = ("\r\n".join(lines) + "\r\n\r\n").encode() + body
    foreign = host_kind == "foreign" or origin_kind == "foreign"
    return Request(data, foreign, host is None)


GARBAGE = [b"\r\n\r\n", b"GET\r\n\r\n", b"GET / HTTP/9.9\r\n\r\n", b"\x16\x03\x01\x02\x00"]
GARBAGE += [b"GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n", b"GET /\x00 HTTP/1.1\r\n\r\n"]
GARBAGE += [b"GET / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\nzz\r\n", b"A" * 70000]


def garbage() -> st.SearchStrategy[Request]:
    """Bytes that are not a well-formed request (answered 4xx, or the connection closed):
    fixed oddities, random bytes, a request with a method no server knows."""
    odd_method = st.tuples(TOKEN, st.sampled_from(PATHS)).map(
        lambda m: f"{m[0]} {m[1]} HTTP/1.1\r\nConnection: close\r\n\r\n".encode()
    )
    raw = st.one_of(st.sampled_from(GARBAGE), st.binary(min_size=1, max_size=300), odd_method)
    return raw.map(Request)


def status_of(port: int, data: bytes, done: bool = False) -> int | None:
    """Send ``data`` (then end the stream if ``done``: nothing more will come); the status
    of the answer, None if the server closed without one."""
    with socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT) as conn:
        with contextlib.suppress(ConnectionResetError, BrokenPipeError):
            conn.sendall(data)
            if done:
                conn.shutdown(socket.SHUT_WR)
        head = b""
        with contextlib.suppress(ConnectionResetError):
            while b"\r\n" not in head and (chunk := conn.recv(4096)):
                head += chunk
    words = head.split(b"\r\n", 1)[0].split()
    return int(words[1]) if len(words) > 1 and words[1].isdigit() else None


# --- WebSocket messages -------------------------------------------------------------------

LAYER_NAMES = ["walls", "header", "path", "location", "free_space", "frontiers", "nope", ""]
LEAVES: st.SearchStrategy[Any] = st.one_of(
    st.integers(-(2**70), 2**70),
    st.floats(allow_nan=False, allow_infinity=False),
    st.booleans(),
    st.none(),
    st.text(max_size=20),
    st.sampled_from(["frame", "play", "pause", "step", "speed", "A", "B", "base", *LAYER_NAMES]),
)
JSON_VALUES = st.recursive(
    LEAVES,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=30,
)
SENTINEL = 3  # the step of the frame request that closes a session (never drawn)
KNOWN = {"info", "frame", "error", "reload"}  # the types of the server's messages
MAX_FRAME = 1 << 20  # bytes: a larger message closes its socket (protocol.MAX_FRAME)
# sessions every run starts with, whatever hypothesis draws: a message past the limit,
# alone and after a valid one (the socket must close with 1009, and a new page be served)
ANCHORS: list[list[str | bytes]] = [
    ["x" * (MAX_FRAME + 1)],
    ['{"op": "play"}', b"\x00" * (MAX_FRAME + 1)],
]
NUMBERS = st.one_of(st.sampled_from([0, 1, 5, 11, 12, 10**30, -1, 2**63]), st.integers(0, 40))
NUMBERS = NUMBERS.filter(lambda n: n != SENTINEL)
CONTROLS = ["play", "pause", "step", "stop", "speed", "frame", "jump", ""]


@st.composite
def layer_sets(draw: Callable[..., Any]) -> Any:
    """A page's layers object: mostly well-formed, with unknown names or agents at times."""
    team = draw(st.lists(st.sampled_from(LAYER_NAMES), max_size=4))
    robots = draw(
        st.dictionaries(
            st.sampled_from(["A", "B", "base", "Z"]),
            st.lists(st.sampled_from(LAYER_NAMES), max_size=3),
            max_size=3,
        )
    )
    layers: Any = {"team": team, "robots": robots}
    return draw(st.one_of(st.just(layers), JSON_VALUES)) if draw(st.booleans()) else layers


BIG = [" " * (1 << 18) + "{}", "x" * (MAX_FRAME + 1), b"\x00" * 70000]
ODD = ["NaN", '{"op":"speed","value":Infinity}', "[1e400]", "9" * 5000, '{"op":"frame"']


@st.composite
def messages(draw: Callable[..., Any]) -> str | bytes:
    """One message from a page: a request with odd values, random JSON, deep, big, binary."""
    kinds = ["frame"] * 4 + ["control"] * 3 + ["json", "text", "deep"] * 2 + ["big"]
    kind = draw(st.sampled_from(kinds))
    if kind == "frame":
        fields = {"op": "frame", "n": draw(NUMBERS), "layers": draw(layer_sets())}
        return json.dumps({**fields, "known": draw(NUMBERS)})
    if kind == "control":
        return json.dumps({"op": draw(st.sampled_from(CONTROLS)), "value": draw(LEAVES)})
    if kind == "json":
        return json.dumps(draw(JSON_VALUES))
    if kind == "deep":
        depth = draw(st.sampled_from([8, 9, 50, 1000, 100_000]))
        opener, closer = draw(st.sampled_from([("[", "]"), ('{"a":', "}"), ('{"op":', "}")]))
        return opener * depth + "1" + closer * depth
    if kind == "big":
        return draw(st.sampled_from(BIG))
    return draw(st.one_of(st.text(max_size=200), st.binary(max_size=200), st.sampled_from(ODD)))


@dataclass
class Session:
    """What one page saw: replies by type, whether its socket closed and its close code."""

    replies: Counter[str] = field(default_factory=Counter)
    answered: bool = False  # the closing frame request was answered
    close_code: int | None = None


async def page_session(port: int, sent: list[str | bytes]) -> Session:
    """Open a page of the viewer's own, send ``sent``, then ask for the frame of step
    :data:`SENTINEL` and read until it comes (or the socket closes)."""
    url, origin = f"ws://127.0.0.1:{port}/ws", {"Origin": f"http://127.0.0.1:{port}"}
    seen = Session()
    async with (
        aiohttp.ClientSession() as client,
        client.ws_connect(url, headers=origin, max_msg_size=0) as ws,
    ):
        try:
            for message in sent:
                await (ws.send_bytes if isinstance(message, bytes) else ws.send_str)(message)
            await ws.send_json({"op": "frame", "n": SENTINEL, "layers": {}, "known": 0})
        except ConnectionError:  # the server closed the socket while we still sent (reset,
            # or aiohttp's 'Connection lost' when the transport is already gone)
            seen.close_code = ws.close_code or 1006
            return seen
        while not seen.answered:
            msg = await ws.receive(timeout=TIMEOUT)
            if msg.type == aiohttp.WSMsgType.BINARY:  # a frame's PNG
                continue
            if msg.type != aiohttp.WSMsgType.TEXT:
                seen.close_code = ws.close_code
                break
            header = json.loads(msg.data)
            seen.replies[str(header.get("type"))] += 1
            seen.answered = header.get("type") == "frame" and header.get("n") == SENTINEL
    return seen


# --- judging ---------------------------------------------------------------------------------


@dataclass
class Tally:
    """Counts of what the server answered, and the failures seen with their cases."""

    counts: Counter[str] = field(default_factory=Counter)
    failures: list[tuple[str, str]] = field(default_factory=list)

    def fail(self, case: Any, why: str) -> None:
        self.counts["failures"] += 1
        self.failures.append((repr(case)[:300], why))


class Errors(logging.Handler):
    """Every error the server's loggers (aiohttp, asyncio, mresim_phys) report."""

    def __init__(self) -> None:
        super().__init__(logging.ERROR)
        self.seen: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.seen.append(self.format(record))


def judge_request(tally: Tally, port: int, request: Request, well_formed: bool) -> None:
    """Send one request; a 5xx, a foreign Host or Origin not refused, no answer: failures."""
    try:
        status = status_of(port, request.data, done=not well_formed)
    except OSError as exc:  # a timeout: the server did not answer
        tally.fail(request, f"no answer: {exc!r}")
        return
    tally.counts[f"http {status or 'closed'}"] += 1
    if status is not None and status >= 500:
        tally.fail(request, f"answered {status}")
    elif well_formed and request.foreign and status != 403:
        if not (request.hostless and status == 400):
            tally.fail(request, f"a foreign Host or Origin answered {status}, not 403")
    elif well_formed and status is None:
        tally.fail(request, "closed without an answer")


def judge_session(tally: Tally, port: int, sent: list[str | bytes]) -> None:
    """Run one page's session: its last request answered, unless a message past the
    socket's limit closed it (1009; 1006 if the connection was reset while the client
    still sent), and then a new page must be served."""
    try:
        seen = asyncio.run(page_session(port, sent))
    except (aiohttp.ClientError, asyncio.TimeoutError, OSError) as exc:
        tally.fail(sent, f"the page's session failed: {exc!r}")
        return
    tally.counts["ws messages"] += len(sent)
    tally.counts["ws error replies"] += seen.replies["error"]
    tally.counts["ws frames"] += seen.replies["frame"]
    too_big = any(len(m.encode() if isinstance(m, str) else m) > MAX_FRAME for m in sent)
    if seen.close_code is not None:
        tally.counts[f"ws closed {seen.close_code}"] += 1
        if not too_big or seen.close_code not in (1009, 1006):  # 1006: reset while sending
            tally.fail(sent, f"socket closed ({seen.close_code}) without a message too big")
        judge_session(tally, port, [])  # a new page is served
    elif not seen.answered or seen.replies["error"] > len(sent) or set(seen.replies) - KNOWN:
        tally.fail(sent, f"unexpected replies: {dict(seen.replies)}")


# --- many cases ------------------------------------------------------------------------------


def prepare(folder: Path) -> Path:
    """A 12-step run of the small map (robot B fails at step 5), written into ``folder``."""
    from mresim_phys.cli import main

    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(MAP, folder / MAP.name)
    path = folder / "scenario.yaml"
    path.write_text(yaml.safe_dump(SCENARIO, sort_keys=False), encoding="utf-8")
    out = folder / "run"
    if main(["run", str(path), "--quiet", "--no-plots", "--overwrite", "--out", str(out)]) != 0:
        raise RuntimeError(f"the run for the viewer failed ({path})")
    return out


@contextlib.contextmanager
def serving(run_dir: Path, errors: Errors) -> Iterator[Any]:
    """The viewer replaying ``run_dir`` on loopback (any free port), errors recorded."""
    from mresim_phys.viewer.replaysource import ReplaySource
    from mresim_phys.viewer.server import ViewerServer

    loggers = [logging.getLogger(name) for name in ("aiohttp", "asyncio", "mresim_phys")]
    for logger in loggers:
        logger.addHandler(errors)
    server = ViewerServer(ReplaySource.open(run_dir), "127.0.0.1", 0)
    server.start()
    try:
        yield server
    finally:
        server.close()
        for logger in loggers:
            logger.removeHandler(errors)


def still_serving(tally: Tally, server: Any) -> None:
    """The server's thread runs and it answers the page (200) in time."""
    thread = server._thread
    if thread is None or not thread.is_alive():
        tally.fail("check", "the server's thread is gone")
        return
    own = f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\nConnection: close\r\n\r\n"
    try:
        status = status_of(server.port, own.encode())
    except OSError as exc:
        status = None
        tally.fail("check", f"the page was not served: {exc!r}")
    tally.counts["checks"] += 1
    if status != 200:
        tally.fail("check", f"the page answered {status}")


@st.composite
def cases(draw: Callable[..., Any], port: int) -> tuple[str, Any]:
    """One case: ('http', a well-formed request), ('garbage', bytes) or ('ws', messages)."""
    kind = draw(st.sampled_from(["http"] * 5 + ["garbage"] + ["ws"] * 4))
    if kind == "http":
        return kind, draw(requests(port))
    if kind == "garbage":
        return kind, draw(garbage())
    return kind, draw(st.lists(messages(), min_size=1, max_size=4))


def fuzz(count: int, folder: Path, seed: int | None = 0) -> Tally:
    """Run ``count`` generated cases at one server (reproducible for a given ``seed``)."""
    run_dir = prepare(folder)
    tally, errors = Tally(), Errors()
    with serving(run_dir, errors) as server:
        port = server.port

        def one(case: tuple[str, Any]) -> None:
            kind, body = case
            tally.counts[f"{kind} cases"] += 1
            if kind == "ws":
                judge_session(tally, port, body)
            else:
                judge_request(tally, port, body, kind == "http")
            if cases_in(tally.counts) % CHECK_EVERY == 0:
                still_serving(tally, server)

        for too_big in ANCHORS:  # every run meets the socket's limit at least once
            tally.counts["ws cases"] += 1
            judge_session(tally, port, too_big)
        run_cases(count, seed, cases(port), one)
        still_serving(tally, server)
    for error in errors.seen:
        tally.fail("the server's log", error)
    return tally


def cases_in(counts: Counter[str]) -> int:
    """How many cases ran."""
    return sum(counts[f"{k} cases"] for k in ("http", "garbage", "ws"))


def report(counts: Counter[str]) -> str:
    """The counts as two lines."""
    total = cases_in(counts)
    statuses = ", ".join(
        f"{key.removeprefix('http ')}: {n}"
        for key, n in sorted(counts.items())
        if key.startswith("http ") and key != "http cases"
    )
    closed = sum(n for key, n in counts.items() if key.startswith("ws closed"))
    return (
        f"{total} cases: {counts['http cases']} requests and {counts['garbage cases']} non-HTTP"
        f" byte strings (status {statuses}); {counts['ws cases']} page sessions,"
        f" {counts['ws messages']} messages: {counts['ws error replies']} error replies,"
        f" {counts['ws frames']} frames, {closed} sockets closed (message > 1 MiB);\n"
        f"{counts['checks']} checks that the page is served; {counts['failures']} failures"
    )


def main(argv: list[str] | None = None) -> int:
    """Print the counts of ``--count`` fuzzed cases; exit 1 if any failed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=1000, help="cases to generate (1000)")
    parser.add_argument("--seed", type=int, default=0, help="hypothesis seed (0)")
    parser.add_argument("--show", type=int, default=5, help="failures to print in full (5)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="mresim-fuzz-viewer-") as work:
        tally = fuzz(args.count, Path(work), args.seed)
    print(report(tally.counts))
    for case, why in tally.failures[: args.show]:
        print("-" * 72, f"\n{case}\n{why}", file=sys.stderr)
    return 1 if tally.failures else 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
