"""``utility_return``: a robot out of the base's reach goes home to report when r = B / (B + N)
drops below its target, explores again once its data has reached the base, and hands its
undelivered cells to a teammate nearer the base."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mresim_phys.knowledge.teammates import TeammateInfo
from mresim_phys.strategies import RobotView
from mresim_phys.strategies.params import UtilityReturnParams
from mresim_phys.strategies.utility_return import DeliveryPayload, UtilityReturn
from mresim_phys.types import FREE, OCCUPIED, UNKNOWN


def corridor(known_until: int, step: int, base_contact: int) -> RobotView:
    """A 20x200 corridor known from column 5 to ``known_until``, the base at its west end,
    the robot near the east end of what it knows."""
    belief = np.full((20, 200), OCCUPIED, dtype=np.uint8)
    belief[5:15, :] = UNKNOWN
    belief[5:15, 5:known_until] = FREE
    return RobotView(
        step=step, name="A", position=(known_until - 10.5, 10.5), heading=0.0, belief=belief,
        radius=1.0, clearance=2.0, speed=2.0, sensor_range=30.0, role="explorer",
        base_position=(8.5, 10.5), teammates={}, rng=np.random.default_rng(0),
        base_contact=base_contact, vary_with_seed=False,
    )  # fmt: skip


def test_in_contact_it_explores_and_owes_nothing() -> None:
    strategy = UtilityReturn(UtilityReturnParams())
    decision = strategy.decide(corridor(60, step=10, base_contact=9))
    assert decision.goal is not None and decision.goal[0] > 50  # the east frontier
    assert isinstance(decision.payload, DeliveryPayload) and decision.payload.undelivered == 0


def test_out_of_contact_it_goes_home_when_the_ratio_drops() -> None:
    strategy = UtilityReturn(UtilityReturnParams(target_ratio=0.9))
    strategy.decide(corridor(60, step=10, base_contact=9))  # B: 10 x 55 cells
    a_little = strategy.decide(corridor(64, step=30, base_contact=9))  # N = 40: r = 0.93
    assert not a_little.info.get("returning") and a_little.goal is not None
    assert a_little.goal[0] > 50
    much = strategy.decide(corridor(90, step=60, base_contact=9))  # N = 300: r = 0.65
    assert much.info.get("returning") and not much.done
    assert much.goal is not None and much.goal[0] < 15  # at the base
    assert isinstance(much.payload, DeliveryPayload) and much.payload.undelivered == 300
    back = strategy.decide(corridor(90, step=90, base_contact=89))  # delivered: explore on
    assert not back.info.get("returning") and back.goal is not None and back.goal[0] > 50


def test_a_teammate_nearer_the_base_takes_over_the_cells_to_deliver() -> None:
    strategy = UtilityReturn(UtilityReturnParams(target_ratio=0.9))
    strategy.decide(corridor(60, step=10, base_contact=9))
    report = DeliveryPayload(undelivered=5, to_base=20.0, step=59)
    mate = TeammateInfo("B", (28.5, 10.5), None, "active", "explorer", step=59, payload=report)
    view = replace(corridor(90, step=60, base_contact=9), teammates={"B": mate}, links=("B",))
    decision = strategy.decide(view)
    assert not decision.info.get("returning")  # B carries the news home
    assert isinstance(decision.payload, DeliveryPayload) and decision.payload.undelivered == 0
    farther = DeliveryPayload(undelivered=5, to_base=150.0, step=59)
    far_mate = replace(mate, payload=farther)
    other = UtilityReturn(UtilityReturnParams(target_ratio=0.9))
    other.decide(corridor(60, step=10, base_contact=9))
    kept = other.decide(replace(view, teammates={"B": far_mate}))
    assert kept.info.get("returning")  # the farther teammate hands nothing to carry for it
