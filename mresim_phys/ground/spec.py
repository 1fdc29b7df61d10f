"""Ground classes (phase 0, input): the scenario's ``ground:`` block and a robot's ``crosses``.

A map layer of named ground classes, each with the speed factor a robot crosses it at
unless the robot says otherwise (0: it cannot enter it)::

    ground:
      classes: {rubble: 0.4, stairs: 0, water: 0}   # name: default factor in [0, 1]
      image: ground.png                             # optional: a colour image the map's size
      legend: {rubble: [150, 110, 60], stairs: [220, 40, 40], water: [40, 90, 220]}  # RGB
      regions:                                      # optional: drawn over the image, in order
        - {ground: stairs, box: [300, 120, 330, 160]}
    team:
      crosses: {rubble: 0.3}        # a robot's own factors, by class (the others: defaults)
    robots:
      - {name: drone, start: [40, 300], crosses: {rubble: 1, stairs: 1, water: 1}}

Every cell not in a class is plain floor (factor 1 for every robot). What each robot can
cross is in docs/ground.md; the grid is built by ``ground/grid.py``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Annotated, ClassVar

from pydantic import Field, field_validator, model_validator

from mresim_phys.strict import Strict
from mresim_phys.world.element_params import ShapedRegion

MAX_CLASSES = 32  # classes a ground layer may name
CLASS_NAME = re.compile(r"[a-z][a-z0-9_]{0,31}")
Colour = tuple[int, int, int]
Factor = Annotated[float, Field(ge=0, le=1)]  # a speed factor on a class (0: cannot enter)


class GroundRegion(ShapedRegion):
    """A region of one ground class: one of ``box``, ``circle``, ``polygon``, ``mask``."""

    KIND: ClassVar[str] = "a ground region"
    ground: str = Field(description="The class of its cells (a name of ground.classes).")


class GroundSpec(Strict):
    """The ground classes of the map, from an image with a legend and/or regions."""

    classes: dict[str, Factor] = Field(
        min_length=1,
        max_length=MAX_CLASSES,
        description=(
            "Each class's name (lower case letters, digits, '_') and the speed factor a robot"
            " crosses it at unless its crosses say otherwise (0: it cannot enter)."
        ),
    )
    image: Path | None = Field(
        None, description="A colour image the size of the map; its legend names the colours."
    )
    legend: dict[str, Colour] | None = Field(
        None, description="The image's colour [r, g, b] of each class; other colours: floor."
    )
    regions: list[GroundRegion] | None = Field(
        None, description="Regions of a class each, drawn over the image in order (later wins)."
    )

    @field_validator("classes")
    @classmethod
    def _names_and_factors(cls, classes: dict[str, float]) -> dict[str, float]:
        for name in classes:
            if not CLASS_NAME.fullmatch(name):
                raise ValueError(
                    f"class name {name!r}: 1 to 32 lower case letters, digits or '_',"
                    " starting with a letter"
                )
        return classes

    @model_validator(mode="after")
    def _sources(self) -> GroundSpec:
        if self.image is None and not self.regions:
            raise ValueError("give an 'image' with its 'legend', 'regions', or both")
        if (self.image is None) != (self.legend is None):
            raise ValueError("an 'image' needs a 'legend' naming its colours, and only an image")
        named = set(self.legend or {}) | {r.ground for r in self.regions or []}
        unknown = sorted(named - set(self.classes))
        if unknown:
            raise ValueError(
                f"{unknown} not among the classes {sorted(self.classes)}: name every class"
                " of the legend and the regions in 'classes'"
            )
        colours = list((self.legend or {}).values())
        bad = [
            name for name, rgb in (self.legend or {}).items() if not all(0 <= v <= 255 for v in rgb)
        ]
        if bad:
            raise ValueError(f"legend colours of {bad}: each of r, g, b is 0 to 255")
        if len(set(colours)) != len(colours):
            raise ValueError("two classes of the legend have the same colour")
        return self

    @property
    def names(self) -> tuple[str, ...]:
        """The classes in order: class i + 1 of the grid is ``names[i]`` (0: floor)."""
        return tuple(self.classes)


def check_team_crosses(
    ground: GroundSpec | None, robots: list[tuple[str, dict[str, float]]]
) -> None:
    """Every class a robot's ``crosses`` names is a ground class (``robots``: (name,
    crosses) of the robots that give any)."""
    for name, crosses in robots:
        if ground is None:
            raise ValueError(
                f"robot {name!r} has 'crosses' but the scenario has no 'ground:' block naming"
                " ground classes; add one (docs/ground.md) or drop 'crosses'"
            )
        unknown = sorted(set(crosses) - set(ground.classes))
        if unknown:
            raise ValueError(
                f"robot {name!r}: crosses names {unknown}, not ground classes; the classes"
                f" are {sorted(ground.classes)}"
            )
