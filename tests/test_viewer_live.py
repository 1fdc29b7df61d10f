"""``mresim run --view`` driven over its WebSocket (no browser): same results, real pause,
single steps, stop writing the run's outputs."""

from __future__ import annotations

import asyncio
import json
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import aiohttp

from mresim_phys.cli import main

MakeScenario = Callable[..., Path]
LAYERS = {"team": ["walls", "header"], "robots": {"A": ["location", "path"]}}


@contextmanager
def viewed_run(
    scenario: Path, out: Path, *flags: str
) -> Iterator[tuple[str, subprocess.Popen[str]]]:
    """``mresim run SCENARIO --view --port 0`` in a child process: (ws URL, process)."""
    command = [sys.executable, "-m", "mresim_phys.cli", "run", str(scenario), "--view"]
    command += ["--port", "0", "--quiet", "--no-plots", "--out", str(out), *flags]
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None
        line = child.stdout.readline()
        found = re.search(r"http://([\d.]+:\d+)/", line)
        assert found, (line, child.stderr.read() if child.poll() is not None else "")
        yield f"ws://{found.group(1)}/ws", child
    finally:
        if child.poll() is None:
            child.send_signal(signal.SIGTERM)
        try:
            child.communicate(timeout=30)
        except subprocess.TimeoutExpired:  # never leave a server behind
            child.kill()
            child.communicate()


async def frames(ws: aiohttp.ClientWebSocketResponse, count: int) -> list[dict[str, Any]]:
    """Ask for ``count`` frames one after the other; their headers."""
    headers = []
    for _ in range(count):
        await ws.send_json({"op": "frame", "n": 0, "layers": LAYERS, "known": 0})
        headers.append(await next_frame(ws))
    return headers


async def next_frame(ws: aiohttp.ClientWebSocketResponse) -> dict[str, Any]:
    """The next frame header (its PNG checked and skipped); info messages skipped."""
    while True:
        message = await ws.receive_json(timeout=30)
        if message["type"] == "frame":
            png = await ws.receive_bytes(timeout=30)
            assert png[:8] == b"\x89PNG\r\n\x1a\n"
            return dict(message)
        assert message["type"] in ("info", "reload"), message


def drive(url: str, script: Callable[[aiohttp.ClientWebSocketResponse], Any]) -> Any:
    async def go() -> Any:
        async with aiohttp.ClientSession() as session, session.ws_connect(url) as ws:
            info = await ws.receive_json(timeout=30)
            assert info["type"] == "info" and info["mode"] == "live"
            return await script(ws)

    return asyncio.run(go())


async def pause_step_play(ws: aiohttp.ClientWebSocketResponse) -> dict[str, int]:
    """Pause, check the simulation holds, take two single steps, play to the end."""
    await frames(ws, 3)
    await ws.send_json({"op": "pause"})
    paused = (await frames(ws, 2))[-1]["step"]
    time.sleep(1.0)
    held = (await frames(ws, 1))[0]["step"]
    await ws.send_json({"op": "step"})
    await ws.send_json({"op": "step"})
    time.sleep(0.5)
    stepped = (await frames(ws, 1))[0]["step"]
    await ws.send_json({"op": "play"})
    while not (await frames(ws, 1))[0]["finished"]:
        pass
    return {"paused": paused, "held": held, "stepped": stepped}


def test_a_viewed_run_gives_the_same_bytes_and_really_pauses(
    scenario_file: MakeScenario, tmp_path: Path
) -> None:
    path = scenario_file(steps=400, stop={"all_done": False, "stalled_for": None})
    plain = tmp_path / "plain"
    assert main(["run", str(path), "--quiet", "--no-plots", "--out", str(plain)]) == 0
    with viewed_run(path, tmp_path / "viewed", "--steps", "400") as (url, child):
        seen = drive(url, pause_step_play)
        child.send_signal(signal.SIGTERM)
        assert child.wait(30) == 0
    assert seen["held"] == seen["paused"]
    assert seen["stepped"] == seen["paused"] + 2
    for name in ("metrics.csv", "log/steps.jsonl"):
        assert (tmp_path / "viewed" / name).read_bytes() == (plain / name).read_bytes()


async def stop_now(ws: aiohttp.ClientWebSocketResponse) -> int:
    await frames(ws, 2)
    await ws.send_json({"op": "pause"})
    step = int((await frames(ws, 2))[-1]["step"])
    await ws.send_json({"op": "stop"})
    return step


def test_stop_ends_the_run_and_writes_its_outputs(
    scenario_file: MakeScenario, tmp_path: Path
) -> None:
    path = scenario_file(steps=5000, stop={"all_done": False, "stalled_for": None})
    out = tmp_path / "viewed"
    with viewed_run(path, out) as (url, child):
        step = drive(url, stop_now)
        deadline = time.monotonic() + 30
        while not (out / "summary.json").is_file() and time.monotonic() < deadline:
            time.sleep(0.1)
        summary = json.loads((out / "summary.json").read_text())
        assert child.poll() is None  # still serving the finished run
    assert summary["stop_reason"] == "interrupted" and summary["signal"] == "viewer"
    assert summary["steps"] == step  # stopped where it was paused
    rows = (out / "metrics.csv").read_text().splitlines()
    assert len(rows) == step + 2 and (out / "final.png").is_file()
    assert json.loads((out / "log" / "meta.json").read_text())["closed"] is True
