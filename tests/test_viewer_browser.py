"""The viewer in a real browser: Debian's chromium driven by Playwright (CI installs it).

Frames are read back from the page's canvas and compared, pixel for pixel, with what the
renderer draws for the same step and layers from the run log (as ``mresim replay`` does).
"""

from __future__ import annotations

import base64
import json
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
from conftest import write_scenario

from mresim_phys.cli import main
from mresim_phys.output.replay import replay_regions, run_scenario
from mresim_phys.output.runlog import RunLog
from mresim_phys.render import Renderer, frame_scale, parse_layers
from mresim_phys.viewer.replaysource import ReplaySource
from mresim_phys.viewer.server import ViewerServer

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
MakeScenario = Callable[..., Path]
Page = Any  # playwright.sync_api.Page (imported only when chromium is here)

pytestmark = pytest.mark.skipif(
    not Path(CHROMIUM).is_file(), reason="needs chromium (apt-get install chromium)"
)


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
        yield launched
        launched.close()


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 40-step run over the tiny rooms map; robot B fails at step 12."""
    folder = tmp_path_factory.mktemp("viewer")
    path = write_scenario(folder, steps=40, events=[{"step": 12, "fail": "B"}])
    out = folder / "run"
    assert main(["run", str(path), "--quiet", "--no-plots", "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def server(run_dir: Path) -> Iterator[ViewerServer]:
    viewer = ViewerServer(ReplaySource.open(run_dir), "127.0.0.1", 0)
    viewer.start()
    yield viewer
    viewer.close()


@pytest.fixture
def page(browser: Any) -> Iterator[Page]:
    context = browser.new_context(viewport={"width": 1300, "height": 900})
    opened = context.new_page()
    opened.errors = []
    opened.on("console", lambda m: m.type == "error" and opened.errors.append(m.text))
    opened.on("pageerror", lambda e: opened.errors.append(str(e)))
    yield opened
    context.close()


def open_viewer(page: Page, url: str) -> None:
    page.goto(url)
    page.wait_for_function("window.viewer.frames > 0", timeout=15000)


def shown(page: Page) -> np.ndarray:
    """The canvas's pixels as a BGR array (read back losslessly as PNG)."""
    url = page.evaluate("document.getElementById('frame').toDataURL('image/png')")
    data = base64.b64decode(url.split(",", 1)[1])
    return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)


def rendered(run_dir: Path, step: int, layers: str) -> np.ndarray:
    """The frame ``mresim replay`` draws for ``step`` with ``layers``."""
    log = RunLog.open(run_dir / "log")
    regions = replay_regions(run_scenario(run_dir), log.truth)
    shape = log.truth.shape
    renderer = Renderer(shape, parse_layers(layers), frame_scale(shape, 1.0), regions=regions)
    for snap in log.snapshots():
        if snap.step == step:
            return renderer.render(snap)
    raise AssertionError(f"no step {step}")


def scrub(page: Page, n: int) -> None:
    page.eval_on_selector(
        "#scrub", "(el, n) => { el.value = n; el.dispatchEvent(new Event('input')); }", n
    )
    page.wait_for_function(f"window.viewer.n === {n} && !window.viewer.inflight", timeout=10000)


def new_frame(page: Page, action: Callable[[], None]) -> None:
    """Do ``action`` and wait for the frame it brings."""
    before = page.evaluate("window.viewer.frames")
    action()
    page.wait_for_function(
        f"window.viewer.frames > {before} && !window.viewer.inflight", timeout=10000
    )


def test_the_page_loads_without_errors_and_play_advances(page: Page, server: ViewerServer) -> None:
    open_viewer(page, server.url)
    assert page.inner_text("#step") == "0" and page.inner_text("#mode") == "replay"
    page.click("#play")
    page.wait_for_function("Number(document.getElementById('step').textContent) >= 5")
    page.click("#play")
    assert page.errors == []


def test_scrubbing_to_step_k_shows_frame_k(page: Page, server: ViewerServer, run_dir: Path) -> None:
    open_viewer(page, server.url)
    for k in (33, 7):
        scrub(page, k)
        assert page.inner_text("#step") == str(k)
        np.testing.assert_array_equal(shown(page), rendered(run_dir, k, "default"))


def test_toggling_a_layer_changes_the_frame_as_the_renderer_draws_it(
    page: Page, server: ViewerServer, run_dir: Path
) -> None:
    open_viewer(page, server.url)
    scrub(page, 20)
    before = shown(page)
    new_frame(page, lambda: page.click("#layer-A-free_space"))
    after = shown(page)
    assert (after != before).any()
    np.testing.assert_array_equal(after, rendered(run_dir, 20, "default,A:free_space"))
    new_frame(page, lambda: page.click("#team-walls"))
    np.testing.assert_array_equal(shown(page), rendered(run_dir, 20, "default,-walls,A:free_space"))
    assert page.errors == []


def test_keys_play_step_and_toggle_layers(page: Page, server: ViewerServer, run_dir: Path) -> None:
    open_viewer(page, server.url)
    scrub(page, 10)
    new_frame(page, lambda: page.keyboard.press("ArrowRight"))
    assert page.inner_text("#step") == "11"
    new_frame(page, lambda: page.keyboard.press("ArrowLeft"))
    new_frame(page, lambda: page.keyboard.press("3"))  # column 3: free_space, every robot
    assert page.is_checked("#all-free_space") and page.is_checked("#layer-B-free_space")
    np.testing.assert_array_equal(
        shown(page), rendered(run_dir, 10, "default,A:free_space,B:free_space")
    )
    page.keyboard.press(" ")
    page.wait_for_function("Number(document.getElementById('step').textContent) > 11")
    page.keyboard.press(" ")
    assert page.evaluate("window.viewer.playing") is False


def test_hovering_a_robot_shows_its_state(page: Page, server: ViewerServer) -> None:
    open_viewer(page, server.url)
    scrub(page, 30)
    robot = page.evaluate("window.viewer.agents.find(a => a.name === 'B')")
    box = page.locator("#frame").bounding_box()
    size = page.evaluate("[frame.width, frame.height]")
    x = box["x"] + robot["px"][0] * box["width"] / size[0]
    y = box["y"] + robot["px"][1] * box["height"] / size[1]
    page.mouse.move(x, y)
    text = page.inner_text("#hover")
    assert "B (robot)" in text and "failed" in text and "battery" in text and "base heard" in text


def test_an_event_mark_jumps_to_its_step(page: Page, server: ViewerServer) -> None:
    open_viewer(page, server.url)
    marks = page.locator("#marks .mark")
    assert marks.count() >= 1 and "fail B" in (marks.first.get_attribute("title") or "")
    new_frame(page, lambda: marks.first.click())
    assert page.inner_text("#step") == "12"


def test_a_live_run_pauses_steps_and_stops_from_the_page(
    page: Page, tmp_path: Path, run_dir: Path
) -> None:
    path = write_scenario(tmp_path, steps=5000, stop={"all_done": False, "stalled_for": None})
    out = tmp_path / "live"
    command = [sys.executable, "-m", "mresim_phys.cli", "run", str(path), "--view", "--port", "0"]
    command += ["--quiet", "--no-plots", "--out", str(out)]
    child = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None
        url = re.search(r"http://\S+/", child.stdout.readline())
        assert url, "no URL printed"
        open_viewer(page, url.group(0))
        assert page.inner_text("#mode") == "live"
        page.select_option("#speed", "50")
        page.wait_for_function("window.viewer.step >= 10")  # playing: the run advances
        page.click("#play")  # pause
        page.wait_for_function("!window.viewer.playing")
        new_frame(page, lambda: page.evaluate("requestFrame()"))
        paused = page.evaluate("window.viewer.step")
        time.sleep(1.0)
        new_frame(page, lambda: page.click("#layer-A-free_space"))
        assert page.evaluate("window.viewer.step") == paused  # the simulation waited
        page.click("#fwd")
        page.wait_for_function(f"window.viewer.step === {paused + 1}")
        page.click("#stop")
        page.wait_for_function("document.getElementById('mode').textContent === 'replay'")
        summary = json.loads((out / "summary.json").read_text())
        assert summary["steps"] == paused + 1 and summary["signal"] == "viewer"
        assert page.errors == []
    finally:
        child.send_signal(signal.SIGTERM)
        try:
            child.communicate(timeout=30)
        except subprocess.TimeoutExpired:  # never leave a server behind
            child.kill()
            child.communicate()


def test_a_runs_video_plays_in_chromium(page: Page, tmp_path: Path) -> None:
    """The default .mp4 (H.264, yuv420p, faststart) loads and plays in Chromium; OpenCV's
    mp4v, the old default, has no supported source there."""
    path = write_scenario(tmp_path, steps=30)
    for name, codec in (("h264.mp4", []), ("mp4v.mp4", ["--codec", "mp4v"])):
        flags = ["--video", str(tmp_path / name), *codec, "--quiet", "--no-plots", "--no-log"]
        assert main(["run", str(path), "--out", str(tmp_path / name.split(".")[0]), *flags]) == 0
    html = tmp_path / "page.html"
    html.write_text(
        '<video id="h" src="h264.mp4" muted></video><video id="m" src="mp4v.mp4" muted></video>'
    )
    page.goto(html.as_uri())
    page.wait_for_function("document.getElementById('h').readyState >= 2", timeout=15000)
    assert page.evaluate("document.getElementById('h').videoWidth") > 0
    page.evaluate("document.getElementById('h').play()")
    page.wait_for_function("document.getElementById('h').currentTime > 0.3", timeout=15000)
    page.wait_for_function("document.getElementById('m').error !== null", timeout=15000)
    assert page.evaluate("document.getElementById('m').error.code") == 4  # not supported


def test_the_wheel_zooms_about_the_cursor_drag_pans_and_hover_follows(
    page: Page, server: ViewerServer
) -> None:
    open_viewer(page, server.url)
    scrub(page, 5)
    view = page.locator("#view").bounding_box()
    cx, cy = view["x"] + 100, view["y"] + 80
    page.mouse.move(cx, cy)
    for _ in range(4):
        page.mouse.wheel(0, -100)
    zoom = page.evaluate("window.viewer.view.zoom")
    assert zoom == pytest.approx(1.25**4)
    assert page.evaluate("frame.style.imageRendering") == "pixelated"  # crisp from 2x
    box = page.locator("#frame").bounding_box()
    # the point under the cursor stays under it
    size = page.evaluate("[frame.width, frame.height]")
    assert (
        box["width"] == pytest.approx(zoom * view["width"] * 1.0, rel=0.05)
        or box["width"] > view["width"]
    )
    page.mouse.down()
    page.mouse.move(cx - 50, cy - 30)
    page.mouse.up()
    moved = page.evaluate("[window.viewer.view.x, window.viewer.view.y]")
    assert moved[0] < 0 and moved[1] < 0
    robot = page.evaluate("window.viewer.agents.find(a => a.name === 'A')")
    box = page.locator("#frame").bounding_box()
    x = box["x"] + robot["px"][0] * box["width"] / size[0]
    y = box["y"] + robot["px"][1] * box["height"] / size[1]
    page.mouse.move(x, y)
    assert "A (robot)" in page.inner_text("#hover")  # hover finds it where it is drawn now
    page.keyboard.press("z")
    assert page.evaluate("[window.viewer.view.zoom, frame.style.imageRendering]") == [1, "auto"]
    page.keyboard.press("+")
    assert page.evaluate("window.viewer.view.zoom") == pytest.approx(1.25)
    assert page.errors == []


def test_the_robot_table_shows_colours_and_marks_a_failed_robot(
    page: Page, server: ViewerServer
) -> None:
    open_viewer(page, server.url)
    colours = page.evaluate("window.viewer.info.colours")
    assert len(colours) == 3 and len(set(colours)) == 3  # the base and two robots
    cell = "document.querySelector('#robots tr:nth-child(5) td.name')"  # after base and A
    swatch = page.evaluate(f"getComputedStyle({cell}).borderLeftColor")
    b, g, r = (int(colours[2][i : i + 2], 16) for i in (5, 3, 1))
    assert swatch == f"rgb({r}, {g}, {b})"  # robot B's colour, as frames draw it
    scrub(page, 30)
    assert page.inner_text("#status-B") == "failed"
    assert "failed" in (page.get_attribute("#status-B", "class") or "")
    assert page.inner_text("#status-A") != "failed"


def test_every_robot_under_the_cursor_is_listed(page: Page, server: ViewerServer) -> None:
    open_viewer(page, server.url)
    scrub(page, 0)
    page.evaluate(
        "window.viewer.agents = window.viewer.agents.map(a => a.kind === 'robot'"
        " ? {...a, px: [40, 40]} : a)"
    )  # both robots drawn on one spot, as robots that meet are
    box = page.locator("#frame").bounding_box()
    size = page.evaluate("[frame.width, frame.height]")
    page.mouse.move(box["x"] + 40 * box["width"] / size[0], box["y"] + 40 * box["height"] / size[1])
    text = page.inner_text("#hover")
    assert "A (robot)" in text and "B (robot)" in text


def test_events_are_marked_on_the_chart(page: Page, server: ViewerServer) -> None:
    open_viewer(page, server.url)
    scrub(page, 39)
    steps = page.evaluate("window.viewer.info.steps")
    width = page.evaluate("document.getElementById('chart').width")
    x = round(12 / max(steps - 1, 1) * width)
    chart = "document.getElementById('chart').getContext('2d')"
    pixel = page.evaluate(f"Array.from({chart}.getImageData({x}, 3, 1, 1).data)")
    assert pixel[:3] == [204, 51, 51] and pixel[3] > 0  # the red tick of B's failure at step 12
