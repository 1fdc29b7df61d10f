"""Composition root, radio: the communication spec -> channels, the network, region probes."""

from __future__ import annotations

import numpy as np

from mresim_phys.comms import COMM_MODELS
from mresim_phys.comms.ledger import Ledger
from mresim_phys.comms.network import Channel, Network
from mresim_phys.comms.regions import RegionProbe
from mresim_phys.rng import Streams
from mresim_phys.scenario.schema import Scenario
from mresim_phys.types import FloatArray
from mresim_phys.world.space import World


def radio_ranges(scenario: Scenario) -> tuple[FloatArray, FloatArray]:
    """Every agent's main-channel range and transmit power (NaN: the model's default)."""
    radios = [scenario.base_station, *scenario.robots]
    ranges = np.array([r.comm_range for r in radios], dtype=float)
    powers = np.array([np.nan if r.comm_power_dbm is None else r.comm_power_dbm for r in radios])
    return ranges, powers


def build_network(scenario: Scenario, streams: Streams, shape: tuple[int, int]) -> Network:
    """The communication phase of ``scenario``: its channels, ledger and exchange rules."""
    spec = scenario.communication
    ranges, powers = radio_ranges(scenario)
    model = COMM_MODELS.make(spec.model, spec.params)
    main = Channel("main", model, ranges, powers, spec.dropout, streams.get("dropout-main"))
    control = None
    if spec.control is not None:
        c = spec.control
        control = Channel(
            "control",
            COMM_MODELS.make(c.model, c.params),
            np.full(len(ranges), c.range),
            powers,
            c.dropout,
            streams.get("dropout-control"),
        )
    return Network(
        main,
        Ledger(shape, len(ranges)),
        control=control,
        multi_hop=scenario.simulation.multi_hop,
        full_maps=spec.maps == "full",
    )


def region_probe(scenario: Scenario, world: World) -> RegionProbe:
    """The probe of ``scenario``'s main channel on ``world`` (live runs and replays)."""
    comm = scenario.communication
    ranges, powers = radio_ranges(scenario)
    return RegionProbe(COMM_MODELS.make(comm.model, comm.params), ranges, powers, world)
