"""Per-robot features (shared): a feature of a robot, owned in one module.

A feature (a battery, and the ones to come) is a :class:`RobotFeature` declared in its own
module with everything about it:

* its per-robot *state*, kept in ``Robot.features[key]`` (``Agent.features``: the base
  station holds the latest observations too) by the code that runs it (the
  battery: ``faults/runtime.py``); a robot without the feature has no entry;
* its *value*: what a strategy sees (``RobotView.features[key]``) and, unless the feature
  is not ``recorded`` (known terrain and the prior map: grids the run's ``truth.npz`` or
  the robot's scans give back), what a snapshot records (``AgentSnapshot.features[key]``;
  an ``omit_empty`` feature records an empty value as no entry); read by
  ``feature.of(view)``;
* the run log's *codec*: the value under ``key`` in each agent's line of ``steps.jsonl``
  (``encode``, ``decode``), so a replay has it back;
* its *label* beside the robot's name in frames (only where its render ``layer`` is on, if
  it names one) and its entry in the viewer's hover row;
* its *metric columns*: ``@column`` registrations in the same module, reading
  ``RobotRecord.features`` (``metrics.py``), which the live run and the replay fill alike.

:data:`FEATURES` lists the features in a fixed order (built-ins first, as entered here by
``module:attribute`` reference and imported on first use; then those registered by other
packages), which is the order of their keys in log lines, labels and hover rows.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar, Generic, Protocol, TypeVar

from numpy.typing import NDArray

from mresim_phys.plugin import named_object

S = TypeVar("S")  # a feature's per-robot state
V = TypeVar("V")  # the value a strategy sees and a snapshot records
G = TypeVar("G", bound=NDArray[Any])  # a grid a robot keeps and its strategy only reads


class HasFeatures(Protocol):
    """A robot's view, snapshot or record: its features' values by key."""

    @property
    def features(self) -> Mapping[str, Any]:
        """Each feature's value, by key (a robot without a feature has no entry)."""
        ...


class RobotFeature(Generic[S, V]):
    """A per-robot feature: ``key`` names its value in views, snapshots, log lines and hover
    rows. Subclasses give :meth:`value` and, for values that are not plain JSON numbers or
    strings, :meth:`encode` and :meth:`decode`."""

    key: ClassVar[str]
    recorded: ClassVar[bool] = True  # False: a strategy sees it; snapshots and logs do not
    omit_empty: ClassVar[bool] = False  # True: an empty value is recorded as no entry
    layer: ClassVar[str | None] = None  # a render layer its label needs (None: always shown)

    def value(self, state: S) -> V:
        """What a strategy sees and a snapshot records of a robot's state."""
        raise NotImplementedError

    def encode(self, value: V) -> Any:
        """``value`` as JSON for the run log's agent line."""
        return value

    def decode(self, raw: Any) -> V:
        """A logged value read back."""
        value: V = raw
        return value

    def label(self, value: V) -> str:
        """Text after the robot's name in frames ('' for none)."""
        return ""

    def hover(self, value: V) -> Any:
        """The viewer's hover-row entry (JSON)."""
        return self.encode(value)

    def of(self, holder: HasFeatures) -> V | None:
        """This feature's value in a view, snapshot or record (None: the robot has none)."""
        found: V | None = holder.features.get(self.key)
        return found

    def state_of(self, states: Mapping[str, Any]) -> S | None:
        """This feature's state among a robot's ``states`` (None: the robot has none)."""
        found: S | None = states.get(self.key)
        return found

    def value_in(self, states: Mapping[str, Any]) -> V | None:
        """The value of this feature's state among a robot's ``states`` (``Robot.features``;
        None: the robot has none)."""
        return self.value(states[self.key]) if self.key in states else None


class PlainFeature(RobotFeature[S, S]):
    """A feature whose value is its state itself (state a strategy may hold: frozen or
    read-only)."""

    def value(self, state: S) -> S:
        """The state itself."""
        return state


class NameSetFeature(RobotFeature[S, frozenset[str]]):
    """A feature whose value is a set of names (broken parts, teammates): logged as a
    sorted list."""

    def encode(self, value: frozenset[str]) -> Any:
        """The names, sorted."""
        return sorted(value)

    def decode(self, raw: Any) -> frozenset[str]:
        """The logged list as a set."""
        return frozenset(raw)


class ReadOnlyGrid(RobotFeature[G, G]):
    """A feature whose state is a grid the robot's code writes; its value is a read-only
    view of it (no copy)."""

    def value(self, state: G) -> G:
        """A read-only view of the grid."""
        view: G = state.view()
        view.flags.writeable = False
        return view


class FeatureList:
    """The run's features in a fixed order: built-ins entered by reference (imported when
    the list is first read), then features registered in code."""

    def __init__(self, built_in: Mapping[str, str]) -> None:
        self._built_in = dict(built_in)  # key -> "module:attribute" of the feature instance
        self._registered: dict[str, RobotFeature[Any, Any]] = {}
        self._all: tuple[RobotFeature[Any, Any], ...] | None = None
        self._recorded: tuple[RobotFeature[Any, Any], ...] = ()

    def register(self, feature: RobotFeature[Any, Any]) -> RobotFeature[Any, Any]:
        """Add a feature after the built-ins; a key already taken is an error."""
        if feature.key in self._built_in or feature.key in self._registered:
            raise ValueError(f"a feature {feature.key!r} is already registered")
        self._registered[feature.key] = feature
        self._all = None
        return feature

    def all(self) -> tuple[RobotFeature[Any, Any], ...]:
        """Every feature, built-ins first."""
        if self._all is None:
            self._all = (*map(named_object, self._built_in.values()), *self._registered.values())
            self._recorded = tuple(f for f in self._all if f.recorded)
        return self._all

    def recorded(self) -> tuple[RobotFeature[Any, Any], ...]:
        """The features snapshots, records, logs, labels and hover rows carry (every step,
        for every robot: found once, with :meth:`all`)."""
        self.all()
        return self._recorded

    def values(self, states: Mapping[str, Any]) -> dict[str, Any]:
        """Each feature's value of a robot's ``states`` (``Robot.features``), in order: what
        its strategy sees."""
        return {f.key: f.value(states[f.key]) for f in self.all() if f.key in states}

    def recorded_values(self, states: Mapping[str, Any]) -> dict[str, Any]:
        """The recorded features' values of a robot's ``states``: what its snapshot and
        its metrics record hold (an empty value of an ``omit_empty`` feature: no entry)."""
        values = ((f, f.value(states[f.key])) for f in self.recorded() if f.key in states)
        return {f.key: v for f, v in values if not f.omit_empty or v}


FEATURES = FeatureList(
    {
        "parts": "mresim_phys.broken_parts:PARTS",  # first: labels read "B [radio] 73%"
        "battery": "mresim_phys.faults.battery:BATTERY",
        "localization": "mresim_phys.localization.feature:LOCALIZATION",
        "radio": "mresim_phys.comms.radio_feature:RADIO",
        "readings": "mresim_phys.readings_feature:READINGS",
        "clock": "mresim_phys.clocks.feature:CLOCK",
        "discovery": "mresim_phys.discovery_feature:DISCOVERY",
        "terrain": "mresim_phys.knowledge.terrain:TERRAIN",
        "ground": "mresim_phys.ground.feature:GROUND",
        "prior": "mresim_phys.knowledge.prior:PRIOR",
        "payload": "mresim_phys.knowledge.teammates:PAYLOAD",
        "observed": "mresim_phys.knowledge.latest:LATEST",
        "health": "mresim_phys.knowledge.activity:HEALTH",
        "lost": "mresim_phys.knowledge.teammates:LOST",
        "known_area": "mresim_phys.knowledge.known_area:KNOWN_AREA",  # not recorded
    }
)
