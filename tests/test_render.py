"""Views (phase 8): snapshots rendered to frames, layer selection and parsing."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from mresim_phys import Simulation
from mresim_phys.localization.feature import PoseBelief
from mresim_phys.render import (
    DEFAULT_GLOBAL,
    DEFAULT_ROBOT,
    GLOBAL_LAYERS,
    LAYERS,
    ROBOT_LAYERS,
    LayerSpec,
    Renderer,
    Style,
    frame_scale,
    parse_layers,
)
from mresim_phys.render.pose import ellipse_axes
from mresim_phys.snapshot import AgentSnapshot, Snapshot, read_only
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN

ROOT = Path(__file__).resolve().parent.parent
STYLE = Style()
MAP_ONLY = "walls,unexplored,team_known,known_at_base"
ROWS, COLS = 30, 40
# Cells with a known meaning in the hand-built snapshot (row, col).
WALL, UNSEEN, AT_BASE, ROBOT_ONLY = (0, 5), (25, 35), (5, 5), (5, 15)
ONLY_A, ONLY_B = (20, 6), (20, 32)


def agent(name: str, belief: np.ndarray, **kw: object) -> AgentSnapshot:
    fields: dict = {"kind": "robot", "heading": 0.0, "radius": 1.0, "state": "active"}
    fields.update(role="explorer", position=(20.5, 15.5), comm_range=10.0)
    fields["safe"] = np.zeros(belief.shape, bool)
    fields.update(kw)
    return AgentSnapshot(name=name, belief=belief, **fields)


def snapshot(rows: int = ROWS, cols: int = COLS, **robot_a: object) -> Snapshot:
    """Walls on the border; base knows the top-left block; A and B know more of the left
    half; A alone knows (20, 6), B alone (20, 32); (25, 35) is unknown to everyone."""
    truth = np.zeros((rows, cols), bool)
    truth[0, :] = truth[-1, :] = truth[:, 0] = truth[:, -1] = True
    base = np.zeros((rows, cols), np.uint8)
    base[1:10, 1:10] = FREE
    shared = np.zeros((rows, cols), np.uint8)
    shared[1:12, 1:20] = FREE
    shared[0, :20] = OCCUPIED
    a, b = shared.copy(), shared.copy()
    a[18:23, 4:9] = FREE
    b[18:23, 30:35] = FREE
    agents = (
        agent("base", base, kind="base", state="base", role="base", position=(3.5, 3.5)),
        agent("A", a, **robot_a),
        agent("B", b, position=(32.5, 20.5), heading=np.pi),
    )
    links = np.ones((3, 3), bool) & ~np.eye(3, dtype=bool)
    return Snapshot(7, 0.3, 0.1, 2, truth, agents, links)


def render(snap: Snapshot, layers: str = MAP_ONLY, scale: float = 1.0) -> np.ndarray:
    return Renderer(snap.truth.shape, parse_layers(layers), scale).render(snap)


def pixel(frame: np.ndarray, rc: tuple[int, int]) -> tuple[int, ...]:
    return tuple(int(v) for v in frame[rc])


@pytest.mark.parametrize("scale", [1.0, 2.0, 0.5, 0.37])
@pytest.mark.parametrize("shape", [(30, 40), (21, 33), (7, 5)])
def test_frame_is_even_bgr_uint8(shape: tuple[int, int], scale: float) -> None:
    snap = snapshot(*shape)
    renderer = Renderer(shape, LayerSpec.all(), scale)
    frame = renderer.render(snap)
    height, width = (max(round(n * scale), 1) for n in shape)
    assert frame.shape == (height + height % 2, width + width % 2, 3)
    assert frame.dtype == np.uint8 and frame.flags.c_contiguous
    assert renderer.size == frame.shape[1::-1]


def test_map_classes_have_the_paper_colours() -> None:
    frame = render(snapshot())
    assert pixel(frame, WALL) == (0, 0, 0)
    assert pixel(frame, UNSEEN) == STYLE.unexplored
    assert pixel(frame, AT_BASE) == STYLE.known_at_base
    assert pixel(frame, ROBOT_ONLY) == STYLE.team_known == (255, 255, 255)
    assert pixel(frame, ONLY_A) == pixel(frame, ONLY_B) == STYLE.team_known


def test_scaled_cells_keep_their_colour() -> None:
    frame = render(snapshot(), scale=3.0)
    r, c = AT_BASE
    assert (frame[3 * r : 3 * r + 3, 3 * c : 3 * c + 3] == STYLE.known_at_base).all()


def test_known_at_base_off_falls_back_to_team_known_or_unexplored() -> None:
    snap = snapshot()
    base = np.zeros_like(snap.base.belief)
    base[5, 5] = base[25, 35] = FREE  # (25, 35) is known at base but by no robot
    snap = replace(snap, agents=(replace(snap.base, belief=base), *snap.robots))
    assert pixel(render(snap), UNSEEN) == STYLE.known_at_base
    frame = render(snap, "walls,unexplored,team_known")
    assert pixel(frame, AT_BASE) == STYLE.team_known
    assert pixel(frame, UNSEEN) == STYLE.unexplored


def test_layers_off_show_the_background() -> None:
    frame = render(snapshot(), "known_at_base")
    assert pixel(frame, WALL) == STYLE.background
    assert pixel(frame, UNSEEN) == STYLE.background
    assert pixel(frame, AT_BASE) == STYLE.known_at_base


def test_robot_is_drawn_in_its_colour_at_its_centre() -> None:
    frame = render(snapshot(), MAP_ONLY + ",location")
    assert pixel(frame, (15, 20)) == STYLE.robot_colour(0)
    assert pixel(frame, (20, 32)) == STYLE.robot_colour(1)
    assert STYLE.robot_colour(0) != STYLE.robot_colour(1)


def near(frame: np.ndarray, rc: tuple[int, int], colour: tuple[int, ...], tol: int = 40) -> bool:
    r, c = rc
    patch = frame[r - 6 : r + 7, c - 6 : c + 7].astype(int)
    return bool((np.abs(patch - colour).max(axis=2) <= tol).any())


def test_failed_robot_is_grey_with_a_red_x() -> None:
    frame = render(snapshot(state="failed"), MAP_ONLY + ",location")
    b, g, r = pixel(frame, (15, 20))
    assert r > 180 and g < 80 and b < 80
    assert near(frame, (15, 20), STYLE.failed, tol=10)
    assert not near(frame, (15, 20), STYLE.robot_colour(0), tol=10)


def test_error_robot_is_outlined_red_and_done_robot_is_hollow() -> None:
    frame = render(snapshot(state="error"), MAP_ONLY + ",location")
    assert pixel(frame, (15, 20)) == STYLE.robot_colour(0)
    assert near(frame, (15, 20), STYLE.error, tol=30)
    frame = render(snapshot(state="done"), MAP_ONLY + ",location")
    assert pixel(frame, (15, 20)) == STYLE.unexplored
    assert near(frame, (15, 20), STYLE.robot_colour(0), tol=10)


def test_free_space_for_one_robot_tints_only_its_cells() -> None:
    snap = snapshot()
    frame = render(snap, MAP_ONLY + ",B:free_space")
    assert pixel(frame, ONLY_A) == STYLE.team_known
    tinted = np.array(pixel(frame, ONLY_B))
    assert tinted.tolist() != list(STYLE.team_known)
    towards = np.array(STYLE.robot_colour(1)) - STYLE.team_known
    assert np.dot(tinted - STYLE.team_known, towards) > 0  # moved towards B's colour
    assert pixel(frame, UNSEEN) == STYLE.unexplored
    assert pixel(render(snap), ONLY_B) == STYLE.team_known


def test_safe_space_tints_in_the_robot_colour() -> None:
    safe = np.zeros((ROWS, COLS), bool)
    safe[2:4, 12:14] = True
    frame = render(snapshot(safe=safe), MAP_ONLY + ",A:safe_space")
    assert pixel(frame, (3, 13)) not in (STYLE.team_known, STYLE.known_at_base)
    assert pixel(frame, (6, 13)) == STYLE.team_known


def test_frontiers_are_magenta() -> None:
    frame = render(snapshot(), MAP_ONLY + ",frontiers")
    assert pixel(frame, (11, 15)) == STYLE.frontier  # FREE, next to unknown row 12
    assert pixel(frame, (5, 15)) == STYLE.team_known


def test_overlays_change_pixels_only_when_on() -> None:
    snap = snapshot(path=np.array([[25.5, 15.5], [25.5, 5.5]]), goal=(25.5, 5.5), parent="B")
    plain = render(snap)
    for layer in ("path", "goal", "comm_range", "links", "hierarchy", "header", "legend"):
        assert (render(snap, f"{MAP_ONLY},{layer}") != plain).any(), layer


def test_paths_and_goals_follow_their_own_robots() -> None:
    snap = snapshot(path=np.array([[25.5, 15.5], [25.5, 5.5]]), goal=(25.5, 5.5))
    b = replace(snap.robots[1], path=np.array([[32.5, 20.5], [32.5, 27.5]]), goal=(32.5, 27.5))
    snap = replace(snap, agents=(snap.base, snap.robots[0], b))
    frame = render(snap, MAP_ONLY + ",path,goal,A:-path")
    changed = (frame != render(snap)).any(axis=2)
    assert changed[5, 25] and not changed[12, 25]  # A: its goal only
    assert changed[22, 32] and changed[27, 32]  # B: its path and its goal
    a, b = (np.array(STYLE.robot_colour(i)) for i in (0, 1))
    assert np.abs(frame[22, 32] - b).sum() < np.abs(frame[22, 32] - a).sum()  # B's colour
    frame = render(snap, MAP_ONLY + ",path,B:-path")
    assert np.abs(frame[12, 25] - a).sum() < np.abs(frame[12, 25] - b).sum()
    assert pixel(frame, (22, 32)) == STYLE.team_known


def test_header_and_legend_bands() -> None:
    frame = render(snapshot(), "default", scale=8.0)
    assert pixel(frame, (0, frame.shape[1] - 1)) == STYLE.header_bg
    assert pixel(frame, (frame.shape[0] - 1, frame.shape[1] - 1)) == STYLE.legend_bg


def test_skeleton_and_rendezvous_drawn_when_present() -> None:
    snap = snapshot()
    skeleton = np.zeros((ROWS, COLS), bool)
    skeleton[5, 12:18] = True
    a = replace(snap.robots[0], skeleton=skeleton, rendezvous=np.array([[30, 8]]))
    rich = replace(snap, agents=(snap.base, a, snap.robots[1]))
    frame = render(rich, MAP_ONLY + ",skeleton,rendezvous")
    assert pixel(frame, (5, 14)) == STYLE.skeleton
    assert near(frame, (7, 29), STYLE.robot_colour(0), tol=10)
    assert (render(snap, MAP_ONLY + ",skeleton,rendezvous") == render(snap)).all()


def test_rendering_leaves_the_snapshot_unchanged() -> None:
    snap = snapshot(safe=np.ones((ROWS, COLS), bool))
    frozen = replace(
        snap,
        truth=read_only(snap.truth),
        agents=tuple(
            replace(a, belief=read_only(a.belief), safe=read_only(a.safe)) for a in snap.agents
        ),
    )
    before = [(a.belief.copy(), a.safe.copy()) for a in frozen.agents]
    truth = frozen.truth.copy()
    for scale in (0.5, 1.0, 2.0):
        Renderer(frozen.truth.shape, LayerSpec.all(), scale).render(frozen)
    assert (frozen.truth == truth).all()
    for a, (belief, safe) in zip(frozen.agents, before, strict=True):
        assert (a.belief == belief).all() and (a.safe == safe).all()


@pytest.mark.parametrize("scale", [0.5, 1.0, 2.0])
def test_each_frame_is_a_new_array(scale: float) -> None:
    snap = snapshot()
    renderer = Renderer(snap.truth.shape, LayerSpec.all(), scale)
    first = renderer.render(snap)
    kept = first.copy()
    second = renderer.render(snap)
    assert not np.shares_memory(first, second)
    first[:] = 0
    assert (renderer.render(snap) == kept).all() and (second == kept).all()


def test_wrong_map_shape_is_refused() -> None:
    with pytest.raises(ValueError, match="snapshot map"):
        Renderer((10, 10), LayerSpec()).render(snapshot())


def test_live_simulation_snapshot() -> None:
    sim = Simulation.from_yaml(ROOT / "scenarios" / "01_quickstart.yaml")
    for _ in range(5):
        sim.step()
    snap = sim.snapshot()
    beliefs = [a.belief.copy() for a in snap.agents]
    rows, cols = snap.truth.shape
    for scale in (1.0, 2.0):
        frame = Renderer(snap.truth.shape, LayerSpec.all(), scale).render(snap)
        assert frame.shape == (round(rows * scale), round(cols * scale), 3)
    frame = render(snap, MAP_ONLY + ",location")
    x, y = snap.robots[0].position
    assert pixel(frame, (int(y), int(x))) == STYLE.robot_colour(0)
    wall = np.argwhere(snap.truth)[0]
    assert pixel(frame, tuple(wall)) == STYLE.wall
    at_base = np.argwhere(snap.base.belief == FREE)
    assert any(pixel(frame, tuple(rc)) == STYLE.known_at_base for rc in at_base[:50])
    assert (np.asarray(snap.robots[0].belief) != UNKNOWN).any()
    assert all((a.belief == b).all() for a, b in zip(snap.agents, beliefs, strict=True))


# --- layer selection ---------------------------------------------------------------------


def test_layer_names() -> None:
    assert set(LAYERS) == set(GLOBAL_LAYERS) | set(ROBOT_LAYERS)
    assert {"free_space", "safe_space"}.isdisjoint(DEFAULT_ROBOT)
    assert set(GLOBAL_LAYERS) == DEFAULT_GLOBAL
    assert {"location", "path", "frontiers", "comm_range", "goal"} <= DEFAULT_ROBOT


@pytest.mark.parametrize("text", ["", "default", " default , ", "default,-links,links"])
def test_parse_defaults(text: str) -> None:
    assert parse_layers(text) == LayerSpec()


def test_parse_names_removals_and_robot_overrides() -> None:
    assert parse_layers("all") == LayerSpec.all()
    spec = parse_layers("walls, location")
    assert spec.global_layers == {"walls"} and spec.robot_layers == {"location"}
    spec = parse_layers("-links,-path")
    assert "links" not in spec.global_layers and "path" not in spec.robot_layers
    assert "walls" in spec.global_layers
    spec = parse_layers("default, B:free_space+path-goal, C : -location")
    assert spec.for_agent("B") == (DEFAULT_ROBOT | {"free_space"}) - {"goal"}
    assert spec.for_agent("C") == DEFAULT_ROBOT - {"location"}
    assert spec.for_agent("A") == DEFAULT_ROBOT
    assert parse_layers("B:free_space").global_layers == DEFAULT_GLOBAL


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("fronteirs", "did you mean frontiers"),
        ("default,commrange", "comm_range"),
        ("B:walls", "global"),
        ("B:", "should look like"),
        ("B:free_space+", "should look like"),
        (":path", "should look like"),
        ("B:pth", "did you mean path"),
    ],
)
def test_parse_errors(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        parse_layers(text)


def test_layer_spec_checks_names() -> None:
    with pytest.raises(ValueError, match="walls"):
        LayerSpec(robot_layers=frozenset({"walls"}))
    spec = parse_layers("default,Bob:free_space")
    spec.check_agents(["base", "Bob"])
    with pytest.raises(ValueError, match="did you mean Bob"):
        spec.check_agents(["base", "Bobb"])
    assert hash(spec) == hash(parse_layers("default,Bob:free_space"))


def test_style_palette_limits() -> None:
    with pytest.raises(ValueError, match="palette"):
        Renderer((4, 4), LayerSpec(), style=Style(palette=()))
    assert Style().robot_colour(len(STYLE.palette)) == STYLE.robot_colour(0)


def test_potential_and_through_wall_rendezvous_points_drawn_by_their_layers() -> None:
    snap = snapshot()
    a = replace(
        snap.robots[0], rv_candidates=np.array([[30, 8]]), rv_through_walls=np.array([[10, 8]])
    )
    rich = replace(snap, agents=(snap.base, a, snap.robots[1]))
    plain = render(rich, MAP_ONLY)
    candidates = render(rich, MAP_ONLY + ",rv_candidates")
    walls = render(rich, MAP_ONLY + ",rv_through_walls")
    assert near(candidates, (8, 30), STYLE.robot_colour(0), tol=10)
    assert near(walls, (8, 10), STYLE.robot_colour(0), tol=10)
    assert (candidates != plain).any() and (walls != plain).any()
    assert not (candidates != plain)[:, : plain.shape[1] // 2].any()  # each layer its own


# --- believed poses (localisation) ---------------------------------------------------------

BELIEVED = (30.5, 8.5)  # A's believed position in believed_snapshot(); its true one (20.5, 15.5)


Cov = tuple[float, float, float, float, float, float]  # xx, xy, yy, xt, yt, tt


def believed_snapshot(cov: Cov = (4.0, 0.0, 1.0, 0.0, 0.0, 0.01)) -> Snapshot:
    """``snapshot()`` with robot A believing it is at :data:`BELIEVED` (covariance ``cov``:
    a 95 % ellipse of semi-axes 4.9 cells along x and 2.4 along y)."""
    belief = PoseBelief((*BELIEVED, 0.0), cov, math.dist(BELIEVED, (20.5, 15.5)), 0.0)
    return snapshot(features={"localization": belief})


def bluish(frame: np.ndarray, xy: tuple[float, float], scale: float, tol: int = 70) -> bool:
    """Whether a pixel near robot A's colour (grey, white and green are farther than
    ``tol``) is within 3 pixels of world point ``xy``."""
    c, r = (round(v * scale - 0.5) for v in xy)
    patch = frame[r - 3 : r + 4, c - 3 : c + 4].astype(int)
    return bool((np.abs(patch - STYLE.robot_colour(0)).max(axis=2) <= tol).any())


def test_a_believed_pose_draws_its_circle_line_and_ellipse_where_it_is_believed() -> None:
    snap, scale, layers = believed_snapshot(), 8.0, MAP_ONLY + ",location"
    on, off = render(snap, layers + ",localization", scale), render(snap, layers, scale)
    x, y = BELIEVED
    size = 8 / scale  # the hollow circle's radius: A's glyph (radius 1 cell, 8 px)
    major, minor = math.sqrt(5.991 * 4.0), math.sqrt(5.991 * 1.0)  # cells, along x and y
    marks = [(x + size, y), (x - size, y), (x, y + size), (x, y - size)]  # the circle
    marks += [(x + major, y), (x - major, y), (x, y + minor), (x, y - minor)]  # the ellipse
    marks.append(((x + 20.5) / 2, (y + 15.5) / 2))  # the line from the true position
    for xy in marks:
        assert bluish(on, xy, scale) and not bluish(off, xy, scale), xy
    inside = (round((y - 0.4) * scale), round((x + 0.4) * scale))  # off the line
    assert pixel(on, inside) == pixel(off, inside)  # hollow
    assert not bluish(on, (x, y + major), scale)  # the ellipse lies along x
    assert (render(snap, MAP_ONLY + ",localization", scale) != render(snap, MAP_ONLY, scale)).any()


def test_a_certain_belief_draws_no_ellipse_and_a_path_starts_at_the_believed_position() -> None:
    snap = believed_snapshot((0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
    a = replace(snap.robots[0], path=np.array([[30.5, 24.5]]))
    snap = replace(snap, agents=(snap.base, a, snap.robots[1]))
    frame, scale = render(snap, MAP_ONLY + ",path", 8.0), 8.0
    assert bluish(frame, (30.5, 16.5), scale)  # on the leg from the believed position
    assert not bluish(frame, (25.5, 20.0), scale)  # none from the true one
    certain = snap.robots[0].features["localization"]
    assert ellipse_axes(certain, np.array((16.0, 16.0))) is None


def test_ellipse_axes_follow_the_covariance() -> None:
    cov = (2.5, 1.5, 2.5, 0.0, 0.0, 0.0)  # eigenvalues 4 and 1 along the diagonals
    ellipse = ellipse_axes(PoseBelief((1.0, 1.0, 0.0), cov, 0.0, 0.0), np.array((16.0, 16.0)))
    assert ellipse is not None
    axes, angle = ellipse
    assert axes == (round(16 * math.sqrt(5.991 * 4)), round(16 * math.sqrt(5.991)))
    assert angle % 180 == pytest.approx(45.0)


@pytest.mark.parametrize("layers", ["default", "all", MAP_ONLY + ",location,path,goal"])
def test_robots_without_localisation_draw_the_same_with_the_layer_on_or_off(layers: str) -> None:
    snap = snapshot(path=np.array([[25.5, 15.5], [25.5, 5.5]]), goal=(25.5, 5.5))
    on = render(snap, layers + ",localization", 8.0)
    assert on.tobytes() == render(snap, layers + ",-localization", 8.0).tobytes()


def test_the_legend_names_the_believed_pose_only_where_it_is_drawn() -> None:
    snap, plain = believed_snapshot(), snapshot()
    band = slice(-40, None)  # the legend band at the bottom of the frame
    shown = render(snap, "default", 8.0)[band]
    assert (shown != render(snap, "default,-localization", 8.0)[band]).any()
    hidden = render(snap, "default,A:-localization", 8.0)[band]
    assert (render(plain, "default", 8.0)[band] == hidden).all()


def test_the_upscale_of_small_maps_is_render_min_side(tmp_path: Path) -> None:
    """A 160x120 map is drawn at 640x480 by default, at its own size with min_side 0."""
    from mresim_phys.cli import main

    assert frame_scale((120, 160), 1.0) == 4.0 and frame_scale((120, 160), 1.0, 0) == 1.0
    assert frame_scale((120, 160), 1.0, 320) == 2.0 and frame_scale((600, 800), 1.0) == 1.0
    scenario = Path(__file__).resolve().parent.parent / "scenarios" / "01_quickstart.yaml"
    for side, size in ((640, (480, 640)), (0, (120, 160))):
        out = tmp_path / str(side)
        data = yaml.safe_load(scenario.read_text())
        data["map"]["image"] = str((scenario.parent / data["map"]["image"]).resolve())
        data["render"] = {"min_side": side}
        data["steps"] = 5
        path = tmp_path / f"s{side}.yaml"
        path.write_text(yaml.safe_dump(data))
        assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots", "--no-log"]) == 0
        assert cv2.imread(str(out / "final.png")).shape[:2] == size
