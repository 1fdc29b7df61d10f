"""Rendezvous accounting (meetings/): kept, missed and why, waiting time, outputs and replay."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mresim_phys import Simulation
from mresim_phys.cli import main
from mresim_phys.columns import MEETING_COLUMNS
from mresim_phys.meeting_board import Meeting, MeetingBoard, Outcome, Tally, decode, encode

SPEED, REACH = 2.0, 2.0 + 2.0  # the team's speed; at its point: within speed + AT_POINT cells
A_POINT, B_POINT = (20.0, 30.0), (24.0, 30.0)  # 4 cells apart: linked when both are there
SEED = 5  # the drift test's seed (its noise takes both bodies out of each other's reach)


def go_meet(partner: str, point: tuple[float, float], **extra: Any) -> dict[str, Any]:
    params = {"partner": partner, "point": list(point), "step": 20, "wait": 10, **extra}
    return {"name": "meeting_plugins:GoMeet", "params": params}


def meeting_scenario(
    make: Callable[..., Path], b_depart: int = 12, team: dict[str, Any] | None = None,
    **changes: Any,
) -> Path:  # fmt: skip
    """A waits at its point from about step 7; B sets out at ``b_depart``; ranges of 4 cells
    (disk: linked closer than 8), so they are linked only once both are near their points."""
    team = {"speed": SPEED, "radius": 1.0, "sensor": {"range": 30}, "comm_range": 4, **(team or {})}
    robots = [
        {"name": "A", "start": [8, 20], "heading_deg": 0, "strategy": go_meet("B", A_POINT)},
        {"name": "B", "start": [24, 50], "heading_deg": 0,
         "strategy": go_meet("A", B_POINT, depart=b_depart)},
    ]  # fmt: skip
    base = {"position": [8, 8], "comm_range": 3}
    data = {"steps": 34, "team": team, "robots": robots, "base_station": base}
    return make(**{**data, **changes})


def run_steps(path: Path) -> tuple[Simulation, list[MeetingBoard], list[tuple[float, float]]]:
    """Run to the end; each step's board and A's believed position."""
    sim = Simulation.from_yaml(path)
    boards, a_at = [], []
    for record in sim.iterate():
        assert record.meetings is not None
        boards.append(record.meetings)
        a_at.append(sim.robot("A").believed_position)
    return sim, boards, a_at


def only_outcome(sim: Simulation) -> Outcome:
    assert sim.meetings is not None
    assert len(sim.meetings.outcomes) == 1, sim.meetings.outcomes
    return sim.meetings.outcomes[0]


def test_a_meeting_both_keep_is_kept_with_the_waiting_time(scenario_file: Callable[..., Path]):
    sim, boards, a_at = run_steps(meeting_scenario(scenario_file))
    outcome = only_outcome(sim)
    assert outcome.result == "kept" and outcome.reason is None
    assert outcome.meeting.parties == ("A", "B") and outcome.meeting.planned == 0
    first_there = next(s for s, p in enumerate(a_at) if math.dist(p, A_POINT) <= REACH)
    assert outcome.waited == (outcome.judged - first_there, 0)  # A waited; B came and met
    assert outcome.judged > 12  # B set out at 12
    tally = boards[-1].tally
    assert (tally.planned, tally.kept, tally.missed_total, tally.pending()) == (1, 1, 0, 0)


def test_a_partner_that_fails_makes_it_missed_partner_failed(scenario_file: Callable[..., Path]):
    events = [{"step": 5, "fail": "B"}]
    sim, boards, _ = run_steps(meeting_scenario(scenario_file, events=events))
    outcome = only_outcome(sim)
    assert (outcome.result, outcome.reason) == ("missed", "partner_failed")
    assert outcome.judged == 30  # the window's end: step 20 + wait 10
    assert boards[-1].tally.missed == (1, 0, 0)


def test_a_partner_that_never_comes_is_late(scenario_file: Callable[..., Path]):
    sim, _, _ = run_steps(meeting_scenario(scenario_file, b_depart=100))
    assert (only_outcome(sim).result, only_outcome(sim).reason) == ("missed", "late")


def test_a_blackout_at_the_meeting_makes_it_link_failed(scenario_file: Callable[..., Path]):
    events = [{"step": 0, "until": 100, "blackout": ["B"]}]
    sim, _, _ = run_steps(meeting_scenario(scenario_file, events=events))
    outcome = only_outcome(sim)
    assert (outcome.result, outcome.reason) == ("missed", "link_failed")
    assert outcome.waited[0] is not None and outcome.waited[0] > 0
    assert outcome.waited[1] is not None and outcome.waited[1] > 0


def test_a_drifting_pair_at_its_believed_points_is_link_failed(scenario_file: Callable[..., Path]):
    """Large odometry noise, no correction: both believe they stand at their points, 4
    cells apart, while their bodies are far apart: not linked, the link failed there."""
    alpha = {"odometry": {"alpha": [0.05, 0.02, 0.3, 0.01]}}
    path = meeting_scenario(scenario_file, seed=SEED, team={"localization": alpha})
    sim, _, _ = run_steps(path)
    outcome = only_outcome(sim)
    assert (outcome.result, outcome.reason) == ("missed", "link_failed")
    a, b = sim.robot("A"), sim.robot("B")
    assert math.dist(a.believed_position, A_POINT) <= REACH
    assert math.dist(b.believed_position, B_POINT) <= REACH
    assert math.dist(a.position, b.position) >= 8.0  # the truth: out of each other's reach


def run_cli(path: Path, out: Path, *extra: str) -> Path:
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots", *extra]) == 0
    return out


def test_same_seed_same_bytes_and_replay_equals_live(
    scenario_file: Callable[..., Path], tmp_path: Path
):
    path = meeting_scenario(scenario_file, b_depart=100)
    one, two = run_cli(path, tmp_path / "one"), run_cli(path, tmp_path / "two")
    assert (one / "metrics.csv").read_bytes() == (two / "metrics.csv").read_bytes()
    header = (one / "metrics.csv").read_text().splitlines()[0].split(",")
    assert header[-len(MEETING_COLUMNS) :] == list(MEETING_COLUMNS)
    summary = json.loads((one / "summary.json").read_text())
    assert summary["meetings"]["missed"]["late"] == 1
    assert summary["meetings"]["pairs"]["A-B"]["planned"] == 1
    assert main(["replay", str(one), "--metrics"]) == 0
    replayed = (one / "metrics-replayed.csv").read_bytes()
    assert replayed == (one / "metrics.csv").read_bytes()


def test_replayed_frames_equal_live_frames(scenario_file: Callable[..., Path], tmp_path: Path):
    path = meeting_scenario(scenario_file, events=[{"step": 5, "fail": "B"}])
    run = run_cli(path, tmp_path / "run", "--snapshot", "31")
    assert main(["replay", str(run), "--snapshot", "31"]) == 0
    assert (run / "step-00031.png").read_bytes() == (run / "replay-step-00031.png").read_bytes()


def test_frontier_runs_have_no_meeting_columns(scenario_file: Callable[..., Path], tmp_path: Path):
    run = run_cli(scenario_file(steps=5), tmp_path / "run")
    assert "meetings" not in (run / "metrics.csv").read_text().splitlines()[0]
    assert "meetings" not in json.loads((run / "summary.json").read_text())
    assert "meetings" not in (run / "log" / "steps.jsonl").read_text()


def test_the_board_round_trips_through_the_log_codec():
    meeting = Meeting(("base", "C"), (None, (1.5, 2.25)), 40, 60, 12)
    outcome = Outcome(meeting, 61, "missed", "late", (None, 7))
    board = MeetingBoard(Tally(3, 1, (0, 1, 0), 1), (meeting,), (outcome,))
    assert decode(json.loads(json.dumps(encode(board)))) == board


def test_the_sweep_table_has_the_meeting_columns():
    from mresim_phys.output.meetings import summarise_meetings
    from mresim_phys.sweeps.tables import flatten_summary

    meeting = Meeting(("A", "B"), ((1.0, 1.0), (2.0, 2.0)), 10, 20, 0)
    outcomes = [
        Outcome(meeting, 12, "kept", None, (3, 0)),
        Outcome(meeting, 20, "missed", "link_failed", (5, 4)),
        Outcome(meeting, 5, "superseded"),
    ]
    row = flatten_summary({"meetings": summarise_meetings(outcomes, [meeting])})
    assert (row["meetings_planned"], row["meetings_kept"], row["meetings_missed"]) == (4, 1, 1)
    assert row["meetings_missed_link_failed"] == 1 and row["meetings_superseded"] == 1
    assert row["meeting_keep_rate"] == 0.5 and row["meeting_wait_mean"] == 3.0
