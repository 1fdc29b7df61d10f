"""The viewer without a browser: seeking a run log, frames, timeline, protocol, bad input."""

from __future__ import annotations

import asyncio
import csv
import json
import re
import signal
import socket
import subprocess
import sys
import urllib.error
import urllib.request
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import aiohttp
import cv2
import numpy as np
import pytest
from aiohttp.test_utils import make_mocked_request

import mresim_phys.viewer
from mresim_phys.cli import main
from mresim_phys.localization.feature import PoseBelief
from mresim_phys.metrics import RobotRecord, StepRecord
from mresim_phys.output.runlog import RunLog
from mresim_phys.render import LayerSpec, parse_layers
from mresim_phys.snapshot import AgentSnapshot, Snapshot
from mresim_phys.viewer.frames import agent_row
from mresim_phys.viewer.guard import is_local
from mresim_phys.viewer.protocol import ProtocolError, layer_spec, parse_message
from mresim_phys.viewer.replaysource import ReplaySource
from mresim_phys.viewer.server import ViewerServer
from mresim_phys.viewer.timeline import Timeline

MakeScenario = Callable[..., Path]
FAILS = [{"step": 12, "fail": "B"}]


def run(scenario: Path, out: Path, *flags: str) -> Path:
    code = main(["run", str(scenario), "--quiet", "--no-plots", "--out", str(out), *flags])
    assert code == 0
    return out


@pytest.fixture
def run_dir(scenario_file: MakeScenario, tmp_path: Path) -> Path:
    """A 40-step run whose robot B fails at step 12, with a PNG at step 20."""
    path = scenario_file(steps=40, events=FAILS)
    return run(path, tmp_path / "run", "--snapshot", "20", "--layers", "all")


def frozen(snap: Snapshot) -> dict[str, Any]:
    """The fields of a snapshot a frame depends on, copied."""
    agents = [
        (a.position, a.state, a.belief.copy(), a.safe.copy(), a.path.copy(), a.distance)
        for a in snap.agents
    ]
    lost = None if snap.lost_knowledge is None else snap.lost_knowledge.copy()
    return {
        "step": snap.step,
        "explored": snap.explored,
        "known_at_base": snap.known_at_base,
        "truth": snap.truth.copy(),
        "links": snap.links.copy(),
        "agents": agents,
        "lost": lost,
        "failures": snap.failures,
        "events": snap.events,
    }


def same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    for key in a:
        if key == "agents":
            for x, y in zip(a[key], b[key], strict=True):
                assert x[0] == y[0] and x[1] == y[1] and x[5] == y[5]
                for u, v in zip(x[2:5], y[2:5], strict=True):
                    np.testing.assert_array_equal(u, v)
        elif isinstance(a[key], np.ndarray):
            np.testing.assert_array_equal(a[key], b[key])
        else:
            assert a[key] == b[key], key
    return True


@pytest.mark.parametrize("belief", ["grow", "latest"])
def test_seeking_gives_the_snapshots_of_a_sequential_replay(
    scenario_file: MakeScenario, tmp_path: Path, belief: str
) -> None:
    path = scenario_file(steps=40, events=FAILS, simulation={"belief": belief})
    out = run(path, tmp_path / "run")
    expected = [frozen(s) for s in RunLog.open(out / "log").snapshots()]
    source = ReplaySource.open(out, every=7)
    order = [33, 5, 6, 40, 0, 13, 14, 27, 21, 7, 39, 12, 12, 1]
    for n in order:
        assert same(frozen(source.snapshot(n)), expected[n])
    assert source.snapshot(999).step == 40  # clamped to the last step


def test_a_frame_is_the_pixels_the_run_itself_rendered(run_dir: Path) -> None:
    source = ReplaySource.open(run_dir)
    png = source.frames.png(source.snapshot(20), parse_layers("all"))
    shown = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    written = cv2.imread(str(run_dir / "step-00020.png"), cv2.IMREAD_COLOR)
    np.testing.assert_array_equal(shown, written)
    other = cv2.imdecode(
        np.frombuffer(source.frames.png(source.snapshot(20), LayerSpec()), np.uint8), 1
    )
    assert (other != written).any()  # the layers matter


def test_the_timeline_holds_the_metrics_and_the_failure(run_dir: Path) -> None:
    source = ReplaySource.open(run_dir)
    with (run_dir / "metrics.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    timeline = source.info()["timeline"]
    assert timeline["steps"] == [int(r["step"]) for r in rows]
    assert timeline["explored"] == [round(float(r["explored"]), 5) for r in rows]
    assert timeline["known_at_base"] == [round(float(r["known_at_base"]), 5) for r in rows]
    assert [n for n, text in timeline["events"] if "B" in text] == [12]


def test_hover_rows_follow_the_robots(run_dir: Path) -> None:
    source = ReplaySource.open(run_dir)
    header, _ = source.frame(30, LayerSpec(), 0)
    rows = {row["name"]: row for row in header["agents"]}
    assert rows["B"]["state"] == "failed" and rows["A"]["state"] != "failed"
    assert rows["A"]["distance"] > 0 and rows["A"]["base_contact"] >= 0
    scale = source.frames.size[0] / 80  # the 80-column map drawn at a whole scale
    x, y = source.snapshot(30).agents[1].position
    assert rows["A"]["px"] == pytest.approx([x * scale, y * scale], abs=0.1)


def test_messages_are_checked() -> None:
    names = ["base", "A", "B"]
    spec = layer_spec({"team": ["walls"], "robots": {"A": ["path", "free_space"]}}, names)
    assert spec.global_layers == {"walls"} and spec.for_agent("A") == {"path", "free_space"}
    message = parse_message({"op": "frame", "n": 3, "layers": {"team": []}, "known": 2}, names)
    assert (message.n, message.known) == (3, 2)
    assert parse_message({"op": "speed", "value": 20}, names).value == 20.0
    for bad in (
        {"op": "jump"},
        {"op": "frame", "n": -1, "layers": {}},
        {"op": "frame", "layers": {"team": ["free_space"]}},
        {"op": "frame", "layers": {"robots": {"Z": []}}},
        {"op": "speed", "value": "fast"},
        [1, 2],
    ):
        with pytest.raises(ProtocolError):
            parse_message(bad, names)


def cli(capsys: pytest.CaptureFixture[str], *args: str | Path) -> tuple[int, str]:
    code = main([str(a) for a in args])
    return code, capsys.readouterr().err


def test_a_folder_without_a_log_is_a_user_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, err = cli(capsys, "view", tmp_path)
    assert code == 2 and "no run log here" in err and "Traceback" not in err
    code, err = cli(capsys, "view", tmp_path / "nowhere")
    assert code == 2 and "no such run folder" in err


@pytest.mark.parametrize("damage", ["chunk", "line"])
def test_a_damaged_log_is_a_user_error(
    run_dir: Path, capsys: pytest.CaptureFixture[str], damage: str
) -> None:
    log = run_dir / "log"
    if damage == "chunk":
        (log / "deltas-00000.npz").write_bytes(b"not a zip")
    else:
        lines = (log / "steps.jsonl").read_text().splitlines()
        lines[5] = lines[5][:20]
        (log / "steps.jsonl").write_text("\n".join(lines) + "\n")
    code, err = cli(capsys, "view", run_dir, "--port", "0")
    assert code == 2 and "the run log is damaged" in err and str(log) in err
    assert len(err.strip().splitlines()) == 1


def test_a_port_in_use_is_a_user_error(run_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        code, err = cli(capsys, "view", run_dir, "--port", str(port))
    assert code == 2 and f"port {port}" in err and "already in use" in err


def test_server_flags_need_view(
    scenario_file: MakeScenario, capsys: pytest.CaptureFixture[str]
) -> None:
    code, err = cli(capsys, "run", scenario_file(steps=3), "--port", "9000")
    assert code == 2 and "--port only applies with --view" in err


def test_only_loopback_addresses_are_local() -> None:
    assert is_local("127.0.0.1") and is_local("::1") and is_local("::ffff:127.0.0.1")
    assert not any(is_local(a) for a in ("10.0.0.5", "192.168.1.2", "::ffff:8.8.8.8", "", None))


def middleware_status(server: ViewerServer, remote: str) -> int:
    """What the server's guard answers a request for / from ``remote``."""
    request = make_mocked_request("GET", "/", transport=FakeTransport(remote))

    async def handler(request: Any) -> Any:
        from aiohttp import web

        return web.Response(text="ok")

    response = asyncio.run(server._guarded(request, handler))
    return int(response.status)


class FakeTransport:
    """A transport whose peer is ``remote``."""

    def __init__(self, remote: str) -> None:
        self.remote = remote

    def get_extra_info(self, name: str, default: Any = None) -> Any:
        return (self.remote, 40000) if name == "peername" else default

    def is_closing(self) -> bool:
        return False


def test_the_guard_refuses_other_machines_unless_allowed(run_dir: Path) -> None:
    source = ReplaySource.open(run_dir)
    guarded = ViewerServer(source, "0.0.0.0", 0)
    assert middleware_status(guarded, "127.0.0.1") == 200
    assert middleware_status(guarded, "10.1.2.3") == 403
    assert middleware_status(ViewerServer(source, "0.0.0.0", 0, True), "10.1.2.3") == 200


def test_the_info_message_lists_every_layer_and_agent(run_dir: Path) -> None:
    info = json.loads(json.dumps(ReplaySource.open(run_dir).info()))
    assert info["names"] == ["base", "A", "B"] and info["kinds"] == ["base", "robot", "robot"]
    assert "walls" in info["global_layers"] and "free_space" in info["robot_layers"]
    assert "localization" in info["robot_layers"]  # the page builds its columns from these
    assert info["steps"] == 41 and info["mode"] == "replay"
    assert set(info["layers"]["robots"]["A"]) == set(parse_layers("all").for_agent("A"))


def test_a_localised_robot_s_hover_row_has_its_belief_and_the_path_left_from_it() -> None:
    """The ``localization`` feature's hover entry rides in the row; the path left is
    measured from the believed position, where the path is drawn from."""
    belief = PoseBelief((10.0, 4.0, 0.0), (1.0, 0.0, 1.0, 0.0, 0.0, 0.01), 6.0, 0.0)
    grid = np.zeros((12, 12), dtype=np.uint8)
    robot = AgentSnapshot("A", "robot", (4.0, 4.0), 0.0, 1.0, "active", "explorer", 10.0,
                          grid, grid.astype(bool), path=np.array([[10.0, 8.0]]),
                          features={"localization": belief})  # fmt: skip
    row = agent_row(robot, (0.0, 0.0), 3.0)
    assert row["position"] == [4.0, 4.0] and row["path_left"] == 4.0
    hover = {"believed": [10.0, 4.0], "heading_deg": 0.0, "error": 6.0, "sigma": 1.0}
    assert row["localization"] == hover
    plain = agent_row(replace(robot, features={}), (0.0, 0.0), 3.0)
    assert plain["localization"] is None and plain["path_left"] == 7.21


def outside_address() -> str | None:
    """This machine's address on its network (not loopback), if it has one."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("10.255.255.255", 1))  # no packet is sent
            address = str(probe.getsockname()[0])
        except OSError:
            return None
    return None if is_local(address) else address


def test_a_client_on_another_address_is_refused(run_dir: Path) -> None:
    address = outside_address()
    if address is None:
        pytest.skip("this machine has no address besides loopback")
    server = ViewerServer(ReplaySource.open(run_dir), "0.0.0.0", 0)
    server.start()
    try:
        port = server.port
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(f"http://{address}:{port}/", timeout=10)
        assert refused.value.code == 403 and b"--allow-remote" in refused.value.read()
        refused.value.close()
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=10) as page:
            assert b"viewer.js" in page.read()
    finally:
        server.close()


def test_the_page_needs_nothing_from_the_network() -> None:
    static = Path(mresim_phys.viewer.__file__).parent / "static"
    page = (static / "index.html").read_text(encoding="utf-8")
    links = re.findall(r'(?:src|href)="([^"]+)"', page)
    assert links and all(not re.match(r"\w+://", link) for link in links)
    for link in links:
        if link.startswith("/static/"):
            assert (static / link.removeprefix("/static/")).is_file(), link
    for asset in static.iterdir():
        assert "http://" not in asset.read_text(encoding="utf-8").replace("http://127", "")


def test_mresim_view_serves_until_sigterm(run_dir: Path) -> None:
    command = [sys.executable, "-m", "mresim_phys.cli", "view", str(run_dir), "--port", "0"]
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None
        lines = [child.stdout.readline(), child.stdout.readline()]
        found = re.search(r"(http://127\.0\.0\.1:\d+/)", lines[1])
        assert found, lines
        with urllib.request.urlopen(found.group(1), timeout=10) as page:
            assert b'<canvas id="frame"' in page.read()
        with urllib.request.urlopen(found.group(1) + "static/viewer.js", timeout=10) as script:
            assert b"WebSocket" in script.read()
    finally:
        child.send_signal(signal.SIGTERM)
        try:
            _, err = child.communicate(timeout=30)
        except subprocess.TimeoutExpired:  # never leave a server behind
            child.kill()
            _, err = child.communicate()
    assert child.returncode == 0 and err == ""


def test_a_websocket_from_another_site_is_refused(run_dir: Path) -> None:
    server = ViewerServer(ReplaySource.open(run_dir), "127.0.0.1", 0)
    server.start()

    async def connect(origin: str) -> int:
        async with aiohttp.ClientSession() as session:
            try:
                headers = {"Origin": origin}
                async with session.ws_connect(f"ws://127.0.0.1:{server.port}/ws", headers=headers):
                    return 101
            except aiohttp.WSServerHandshakeError as exc:
                return exc.status

    try:
        assert asyncio.run(connect("http://evil.example")) == 403
        assert asyncio.run(connect(f"http://127.0.0.1:{server.port}")) == 101
    finally:
        server.close()


def test_a_silent_failure_is_marked_once() -> None:
    timeline = Timeline()

    def add(step: int, states: tuple[str, str], events: tuple[str, ...] = ()) -> None:
        robots = tuple(RobotRecord(n, 0.0, s) for n, s in zip("AB", states, strict=True))
        record = StepRecord(step, 0.1 * step, 0.05 * step, 0.0, 2, 0, robots)
        timeline.add(record, events, states)

    add(0, ("active", "active"))
    add(1, ("active", "failed"))  # a random fault: no event of its own
    add(2, ("failed", "failed"), ("fail A",))  # told by its event
    add(3, ("failed", "failed"))
    assert timeline.events == [(1, "B failed"), (2, "fail A")]
    assert timeline.to_json(2)["steps"] == [2, 3] and timeline.to_json(2)["explored"] == [0.2, 0.3]


def test_a_server_starts_from_a_thread_that_runs_an_event_loop(run_dir: Path) -> None:
    """A notebook, or Playwright's sync API, runs an event loop in the caller's thread: the
    server binds and serves in its own thread all the same."""

    async def start_and_fetch() -> int:
        server = ViewerServer(ReplaySource.open(run_dir), "127.0.0.1", 0)
        server.start()
        try:
            async with aiohttp.ClientSession() as session, session.get(server.url) as page:
                return page.status
        finally:
            server.close()

    assert asyncio.run(start_and_fetch()) == 200
