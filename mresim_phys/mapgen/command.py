"""``mresim make-map`` (output edge): draw a procedural map and write its files.

Every mistake (an unknown parameter, a value out of range, a map too small for what its
parameters ask, no room for the robots) is one paragraph naming the parameter, exit 2.
"""

from __future__ import annotations

import argparse

from pydantic import ValidationError

from mresim_phys.errors import MresimError
from mresim_phys.mapgen.generate import generate, write_map
from mresim_phys.mapgen.params import MapRequest


def make_map_command(args: argparse.Namespace) -> int:
    """Draw the map ``args`` ask for into ``args.out``; print what was written."""
    params = dict(args.set)
    request_data = {
        "kind": args.kind,
        "seed": args.seed,
        "width": args.size[0],
        "height": args.size[1],
        "robots": args.robots,
        "radius": args.radius,
        "params": params,
    }
    where = f"make-map {args.kind}"
    try:
        made = generate(MapRequest.model_validate(request_data))
    except ValidationError as exc:
        raise MresimError(f"{where}: {describe(exc)}") from None
    except ValueError as exc:
        raise MresimError(f"{where}: {exc}") from None
    written = write_map(made, args.out)
    print(f"wrote {', '.join(str(p) for p in written)} (grid sha256 {made.sha256[:12]})")
    return 0


def describe(exc: ValidationError) -> str:
    """The first validation error as one line naming the parameter (``--set NAME``)."""
    first = exc.errors()[0]
    name = ".".join(str(part) for part in first["loc"]) or "parameters"
    message = str(first["msg"]).removeprefix("Value error, ")
    return f"{name}: {message} (see docs/procedural-maps.md for each kind's parameters)"
