"""Frames of robots that are not at work (render/draw.py, render/legend.py) and labels placed
apart (render/labels.py): pixel checks on small hand-built frames."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mresim_phys.knowledge.activity import Health
from mresim_phys.render import Renderer, Style, parse_layers
from mresim_phys.render.draw import robot_label
from mresim_phys.render.labels import overlaps, place_labels, text_box
from mresim_phys.render.legend import legend_band
from mresim_phys.snapshot import AgentSnapshot, Snapshot
from mresim_phys.types import FREE

STYLE = Style()
ROWS, COLS = 30, 40
CENTRE = (15, 20)  # pixel (row, col) of robot A at (20.5, 15.5), scale 1
LAYERS = "walls,unexplored,team_known,known_at_base,location"


def robot(name: str, position: tuple[float, float], **kw: object) -> AgentSnapshot:
    """A robot's snapshot; ``activity``: its run-health activity (the ``health`` feature)."""
    activity = kw.pop("activity", "")
    kw.setdefault("features", {"health": Health(str(activity))} if activity else {})
    belief = np.zeros((ROWS, COLS), np.uint8)
    belief[1:12, 1:20] = FREE
    fields: dict = {"kind": "robot", "heading": 0.0, "radius": 1.0, "state": "active"}
    fields |= {"role": "explorer", "comm_range": 10.0, "safe": np.zeros((ROWS, COLS), bool)}
    return AgentSnapshot(name=name, position=position, belief=belief, **(fields | kw))


def snapshot(*robots: AgentSnapshot) -> Snapshot:
    truth = np.zeros((ROWS, COLS), bool)
    truth[0, :] = truth[-1, :] = truth[:, 0] = truth[:, -1] = True
    base = robot("base", (3.5, 3.5), kind="base", state="base", role="base")
    agents = (base, *robots)
    links = np.zeros((len(agents), len(agents)), bool)
    return Snapshot(7, 0.3, 0.1, len(robots), truth, agents, links)


def frame_of(state: str = "active", activity: str = "working") -> np.ndarray:
    a = robot("A", (20.5, 15.5), state=state, activity=activity)
    return Renderer((ROWS, COLS), parse_layers(LAYERS)).render(snapshot(a))


def pixel(frame: np.ndarray, rc: tuple[int, int]) -> tuple[int, ...]:
    return tuple(int(v) for v in frame[rc])


def ring_hits(frame: np.ndarray, colour: tuple[int, int, int], radius: float) -> int:
    """Pixels within 40 of ``colour`` on a circle of ``radius`` around robot A."""
    hits = 0
    for angle in np.linspace(0, 2 * np.pi, 48, endpoint=False):
        r = round(CENTRE[0] + radius * np.sin(angle))
        c = round(CENTRE[1] + radius * np.cos(angle))
        hits += int(np.abs(frame[r, c].astype(int) - colour).max() <= 40)
    return hits


def test_a_working_robot_is_filled_in_its_colour_without_a_ring() -> None:
    frame = frame_of()
    assert pixel(frame, CENTRE) == STYLE.robot_colour(0)
    assert ring_hits(frame, STYLE.stuck, 10) == 0


def test_an_idle_robot_is_grey_inside() -> None:
    frame = frame_of(activity="idle")
    assert pixel(frame, CENTRE) == STYLE.idle
    assert pixel(frame, CENTRE) != pixel(frame_of(), CENTRE)


def test_a_stuck_robot_is_ringed_in_red() -> None:
    frame = frame_of(activity="stuck")
    assert pixel(frame, CENTRE) == STYLE.robot_colour(0)
    assert ring_hits(frame, STYLE.stuck, 10) > 24  # most of the circle (labels cover a bit)


def test_a_fruitless_robot_is_filled_and_ringed_in_grey_not_red() -> None:
    frame = frame_of(activity="fruitless")
    assert pixel(frame, CENTRE) == STYLE.robot_colour(0)
    assert ring_hits(frame, STYLE.idle, 10) > 24 and ring_hits(frame, STYLE.stuck, 10) == 0


def test_a_done_robot_is_hollow_even_when_idle() -> None:
    frame = frame_of("done", "idle")
    assert pixel(frame, CENTRE) == STYLE.unexplored  # the map shows through
    assert pixel(frame, CENTRE) not in (STYLE.idle, STYLE.robot_colour(0))


def test_a_failed_robot_keeps_its_grey_and_red_x_whatever_its_activity() -> None:
    assert np.array_equal(frame_of("failed", ""), frame_of("failed", "stuck"))


@pytest.mark.parametrize(
    ("state", "activity", "label"),
    [
        ("active", "working", "A"),
        ("active", "idle", "A idle"),
        ("error", "stuck", "A stuck"),
        ("active", "fruitless", "A fruitless"),
        ("done", "idle", "A done"),
        ("failed", "", "A"),
        ("active", "", "A"),
    ],
)
def test_labels_say_what_a_robot_not_at_work_is_doing(
    state: str, activity: str, label: str
) -> None:
    assert robot_label(robot("A", (1.0, 1.0), state=state, activity=activity)) == label


def test_the_legend_has_the_state_glyphs_when_robots_are_drawn() -> None:
    red = np.array(STYLE.stuck)
    with_robots = legend_band(400, ["A"], parse_layers("default"), STYLE)
    without = legend_band(400, ["A"], parse_layers("default,-location"), STYLE)
    assert (np.abs(with_robots.astype(int) - red).max(axis=2) <= 40).any()  # the stuck ring
    assert not (np.abs(without.astype(int) - red).max(axis=2) <= 40).any()
    assert (with_robots == np.array(STYLE.idle)).all(axis=2).any()  # the idle fill


def test_labels_at_one_spot_are_placed_apart() -> None:
    labels = [(name, (100, 100), 6.0) for name in ("base", "A", "B", "C", "D")]
    origins = place_labels(labels, STYLE)
    boxes = [text_box(text, org, STYLE) for (text, _, _), org in zip(labels, origins, strict=True)]
    assert all(not overlaps(a, b) for a, b in itertools.combinations(boxes, 2))


def test_a_label_with_room_stays_up_and_right_of_its_robot() -> None:
    origins = place_labels([("A", (100, 100), 6.0), ("B", (300, 100), 6.0)], STYLE)
    assert origins == [(108, 93), (308, 93)]  # the spot draw_label uses


def test_two_robots_at_one_place_get_both_labels_readable() -> None:
    """Both names are drawn where place_labels puts them: no pixel of B's label lies in A's."""
    a = robot("A", (20.5, 15.5))
    b = robot("B", (20.6, 15.6))
    scale = 8.0
    frame = Renderer((ROWS, COLS), parse_layers(LAYERS), scale).render(snapshot(a, b))
    size = max(STYLE.robot_px, scale)
    places = ((3.5, 3.5), (20.5, 15.5), (20.6, 15.6))
    anchors = [tuple(round(v * scale * 16 - 8) >> 4 for v in xy) for xy in places]  # as drawn
    labels = [("base", anchors[0], 5.0), ("A", anchors[1], size), ("B", anchors[2], size)]
    _, spot_a, spot_b = place_labels(labels, STYLE)
    box_a, box_b = text_box("A", spot_a, STYLE), text_box("B", spot_b, STYLE)
    assert not overlaps(box_a, box_b)
    for name, box, index in (("A", box_a, 0), ("B", box_b, 1)):
        x0, y0, x1, y1 = box
        patch = frame[max(y0, 0) : y1, max(x0, 0) : x1].astype(int)
        colour = np.array(STYLE.robot_colour(index))
        assert (np.abs(patch - colour).max(axis=2) <= 60).any(), name
