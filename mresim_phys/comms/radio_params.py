"""Radio-link parameters (phase 0, input): shadowing, burst losses, loss tables, traces,
bandwidth and latency of a channel (``communication:`` and ``communication.control:``).

Pydantic and the standard library only, like :mod:`.params`. Every option is off by
default; with all of them off a channel is exactly what it was before they existed.
Lengths are in cells, as comm-model parameters are (``units: m`` does not convert them).
Formulas: docs/communication.md, "Radio links".
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from mresim_phys.strict import Strict

MAX_LENGTH = 100_000.0  # cells
MAX_DB = 100.0  # dB: a sigma beyond this is a typo, not a radio


class ShadowingSpec(Strict):
    """Log-normal shadowing: a seeded, spatially correlated field in dB, and fast fading."""

    sigma_db: float = Field(ge=0, le=MAX_DB, description="Standard deviation of shadowing (dB).")
    length: float = Field(
        gt=0,
        le=MAX_LENGTH,
        description="Correlation length (cells): the field's correlation is exp(-(h/length)^2).",
    )
    fading_db: float = Field(
        0.0, ge=0, le=MAX_DB, description="Fast fading: a fresh N(0, fading_db) per link and step."
    )


class BurstSpec(Strict):
    """A Gilbert-Elliott channel per link: a good and a bad state, each with its loss rate."""

    good_to_bad: float = Field(ge=0, le=1, description="P(good -> bad) per step.")
    bad_to_good: float = Field(ge=0, le=1, description="P(bad -> good) per step.")
    loss_good: float = Field(0.0, ge=0, le=1, description="Loss probability in the good state.")
    loss_bad: float = Field(1.0, ge=0, le=1, description="Loss probability in the bad state.")

    @model_validator(mode="after")
    def _moves(self) -> BurstSpec:
        if self.good_to_bad + self.bad_to_good <= 0:
            raise ValueError(
                "good_to_bad and bad_to_good are both 0: the chain never moves and has no"
                " stationary state; give one of them a positive probability"
            )
        return self

    @property
    def stationary_bad(self) -> float:
        """The long-run share of steps a link spends in the bad state."""
        return self.good_to_bad / (self.good_to_bad + self.bad_to_good)

    @property
    def stationary_loss(self) -> float:
        """The long-run loss rate: each state's loss weighted by its stationary share."""
        bad = self.stationary_bad
        return bad * self.loss_bad + (1.0 - bad) * self.loss_good


LossRow = tuple[
    Annotated[int, Field(ge=0, le=1000)],
    Annotated[float, Field(ge=0, le=MAX_LENGTH)],
    Annotated[float, Field(ge=0, le=1)],
]


class RadioSpec(Strict):
    """The radio options a channel may turn on (the main and the control channel alike)."""

    shadowing: ShadowingSpec | None = Field(
        None,
        description="Spatially correlated log-normal shadowing {sigma_db, length, fading_db}"
        " added to the signal (path_loss only).",
    )
    bursts: BurstSpec | None = Field(
        None,
        description="Gilbert-Elliott burst losses per link {good_to_bad, bad_to_good,"
        " loss_good, loss_bad}.",
    )
    loss_table: str | list[LossRow] | None = Field(
        None,
        description="Measured loss per step against wall count and distance: a CSV file"
        " (walls,distance,loss) or a list of [walls, distance, loss] rows.",
    )
    trace: str | None = Field(
        None,
        description="A CSV of link quality to replay (step,a,b,up,loss,capacity), relative"
        " to the scenario file.",
    )
    capacity: int | None = Field(
        None, ge=1, le=10**9, description="Bytes per step per link (null: unlimited)."
    )
    radio_capacity: int | None = Field(
        None,
        ge=1,
        le=10**9,
        description="Bytes per step an agent's radio sends over all its links (null: unlimited).",
    )
    latency: int = Field(0, ge=0, le=10_000, description="Steps from sending to delivery, per hop.")
    priority: Literal["base_first", "nearest", "newest", "strategy"] = Field(
        "base_first",
        description="Order of queued map cells: base_first (cells the base lacks, nearest"
        " first), nearest (nearest the sender first), newest (most recent change first) or"
        " strategy (nearest a point the robot's strategy chooses, else base_first).",
    )

    @property
    def bounded(self) -> bool:
        """Whether what a link carries is limited or delayed (the queued exchange runs)."""
        limits = (self.capacity, self.radio_capacity)
        return any(c is not None for c in limits) or self.latency > 0

    @property
    def lossy(self) -> bool:
        """Whether any link-level option beyond the model and dropout is on."""
        return any(
            x is not None for x in (self.shadowing, self.bursts, self.loss_table, self.trace)
        )
