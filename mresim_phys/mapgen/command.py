"""``mresim make-map`` and ``make-set`` (output edge): draw procedural maps, write their files.

Every mistake (an unknown parameter, a value out of range, a map too small for what its
parameters ask, no room for the robots) is one paragraph naming the parameter, exit 2.
"""

from __future__ import annotations

import argparse

from pydantic import ValidationError

from mresim_phys.errors import MresimError
from mresim_phys.mapgen.errors import describe
from mresim_phys.mapgen.generate import generate, write_map
from mresim_phys.mapgen.params import MapRequest
from mresim_phys.mapgen.sets import SetSpec, make_set
from mresim_phys.scenario.yamlfile import read_yaml_file


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


def make_set_command(args: argparse.Namespace) -> int:
    """Draw every instance of the set file ``args.set_file`` into ``args.out``."""
    path = args.set_file
    data = read_yaml_file(path, "Set file", MresimError)
    try:
        spec = SetSpec.model_validate(data)
        index = make_set(spec, args.out, path)
    except ValidationError as exc:
        raise MresimError(f"{path}: {describe(exc)}") from None
    except ValueError as exc:
        raise MresimError(f"{path}: {exc}") from None
    print(
        f"wrote {len(index['instances'])} maps ({index['train']} train, {index['test']} test)"
        f" and {args.out / 'set.yaml'}"
    )
    return 0
