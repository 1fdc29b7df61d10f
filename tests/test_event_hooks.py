"""Events declare what they touch: a new event kind written outside the package needs no
edit of it (a smoke cloud that halves the laser range of the robots inside it), sees the
robots through the event context, and is validated through the registry as the scenario
is read."""

from __future__ import annotations

from typing import Any, ClassVar

import pytest
from conftest import write_scenario
from pydantic import Field

from mresim_phys import Simulation
from mresim_phys.build import run_rules
from mresim_phys.cli import main
from mresim_phys.plugin import Plugin
from mresim_phys.scenario.load import load_scenario
from mresim_phys.world.event_api import EventContext
from mresim_phys.world.event_catalog import EVENTS
from mresim_phys.world.event_params import Box, Changes, EventParams

SMOKE_FACTORS = (1.0, 0.5)  # speed kept, laser range halved


class SmokeParams(EventParams):
    """From ``step`` until before ``until``, robots inside the box ``smoke`` see half as far."""

    smoke: tuple[int, int, int, int] = Field(description="[x0, y0, x1, y1] in cells.")
    until: int = Field(ge=1)
    changes: ClassVar[frozenset[Changes]] = frozenset({"robots"})

    def boxes(self) -> list[tuple[str, Box]]:
        x0, y0, x1, y1 = self.smoke
        return [("smoke", (y0, y1, x0, x1))]


class Smoke(Plugin):
    """Smoke in a region: the lasers of the robots inside it reach half as far."""

    name = "smoke"
    Params = SmokeParams
    params: SmokeParams

    def __init__(self, params: SmokeParams) -> None:
        self.params = params
        self.inside: set[str] = set()

    def apply(self, context: EventContext) -> None:
        p = self.params
        x0, y0, x1, y1 = p.smoke
        now = set()
        if p.step <= context.step < p.until:
            now = {
                r.name
                for r in context.robots
                if r.state != "failed" and x0 <= r.position[0] < x1 and y0 <= r.position[1] < y1
            }
        for name in sorted(now - self.inside):
            context.fail(name, "degraded", SMOKE_FACTORS)
            context.log(f"smoke {name}")
        for name in sorted(self.inside - now):
            context.repair(name, "degraded", SMOKE_FACTORS)
            context.log(f"smoke clears {name}")
        self.inside = now


class Quake(Plugin):
    """An event that declares it changes the world (and does nothing here)."""

    name = "quake"

    class Params(EventParams):
        quake: bool = True
        changes: ClassVar[frozenset[Changes]] = frozenset({"world"})

    def __init__(self, params: EventParams) -> None:
        self.params = params

    def apply(self, context: EventContext) -> None:
        return None


@pytest.fixture
def with_events(monkeypatch: pytest.MonkeyPatch) -> None:
    """Smoke and quake registered for one test (the registry as it was afterwards)."""
    monkeypatch.setattr(EVENTS, "_classes", dict(EVENTS._classes))
    EVENTS.register(Smoke)
    EVENTS.register(Quake)


@pytest.mark.usefixtures("with_events")
def test_a_smoke_event_written_outside_the_package_halves_the_laser_range(
    tmp_path: Any,
) -> None:
    smoke = {"step": 0, "smoke": [0, 0, 20, 60], "until": 15}  # robots A and B start in it
    sim = Simulation.from_yaml(write_scenario(tmp_path, steps=20, events=[smoke]))
    sim.step()
    full = sim.scenario.team.sensor.range
    assert [r.laser.range for r in sim.robots] == [full / 2, full / 2]
    logged: list[str] = []
    for _ in range(19):
        sim.step()
        logged += sim.snapshot().events
    assert all("degraded" not in r.broken for r in sim.robots)  # cleared at step 15 at last
    assert [r.laser.range for r in sim.robots] == [full, full]
    assert any(line.startswith("smoke clears") for line in logged)


@pytest.mark.usefixtures("with_events")
def test_the_event_context_shows_the_robots_read_only(tmp_path: Any) -> None:
    seen: list[Any] = []

    class Look(Smoke):
        def apply(self, context: EventContext) -> None:
            seen.append(context.robots)

    EVENTS._classes["smoke"] = Look
    smoke = {"step": 0, "smoke": [0, 0, 5, 5], "until": 3}
    sim = Simulation.from_yaml(write_scenario(tmp_path, steps=3, events=[smoke]))
    sim.step()
    robots = seen[-1]
    assert [r.name for r in robots] == ["A", "B"]
    assert robots[0].position == pytest.approx(tuple(sim.robots[0].position), abs=3.0)
    assert robots[0].state == "active" and robots[0].broken == ()
    with pytest.raises(AttributeError):
        robots[0].state = "failed"
    assert isinstance(robots, tuple)


@pytest.mark.usefixtures("with_events")
def test_what_an_event_declares_it_changes_decides_the_beliefs(tmp_path: Any) -> None:
    smoke = {"step": 0, "smoke": [0, 0, 5, 5], "until": 3}
    changes_robots = load_scenario(write_scenario(tmp_path, events=[smoke]))
    assert not run_rules(changes_robots).latest
    changes_world = load_scenario(write_scenario(tmp_path, events=[{"step": 5, "quake": True}]))
    assert run_rules(changes_world).latest


@pytest.mark.usefixtures("with_events")
def test_an_event_registered_in_code_is_validated_at_once(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = {"step": 0, "smoke": [0, 0, 5, 5], "until": 0}
    assert main(["validate", str(write_scenario(tmp_path, events=[bad]))]) == 2
    err = capsys.readouterr().err
    assert "events[0].until" in err and "Traceback" not in err
    outside = {"step": 0, "smoke": [0, 0, 500, 5], "until": 4}
    out = str(tmp_path / "o")
    assert (
        main(["run", str(write_scenario(tmp_path, events=[outside])), "--quiet", "--out", out]) == 2
    )
    assert "events[0].smoke: the window" in capsys.readouterr().err


def test_an_event_naming_a_missing_door_names_its_field(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_scenario(tmp_path, events=[{"step": 3, "close": "front"}])
    assert main(["run", str(path), "--quiet", "--out", str(tmp_path / "o")]) == 2
    assert "events[0].close: there is no door called 'front'" in capsys.readouterr().err
