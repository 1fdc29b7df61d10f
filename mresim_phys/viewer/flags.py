"""The viewer's command-line flags (output edge): ``mresim view`` and ``mresim run --view``.

Argument parsing only (the standard library): the ``mresim`` parser is built without
importing the viewer's server or the simulator (``viewer/command.py`` does the work).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from mresim_phys.errors import MresimError

DEFAULT_HOST, DEFAULT_PORT = "127.0.0.1", 8765
VIEW_FLAGS = ("host", "port", "open", "allow_remote", "allow_host")


def add_server_flags(parser: argparse.ArgumentParser) -> None:
    """--host, --port, --open, --allow-remote, --allow-host."""
    parser.add_argument("--host", help=f"address to serve on (default {DEFAULT_HOST})")
    parser.add_argument(
        "--port", type=int, help=f"port to serve on (default {DEFAULT_PORT}; 0: any free port)"
    )
    parser.add_argument("--open", action="store_true", help="open the page in a web browser")
    parser.add_argument(
        "--allow-remote",
        action="store_true",
        help="serve clients on other machines too (refused by default)",
    )
    parser.add_argument(
        "--allow-host",
        action="append",
        metavar="NAME[:PORT]",
        help="also accept this name in a request's Host and Origin (repeatable; e.g. the"
        " name of a proxy in front of the viewer); by default only the served address",
    )


def add_view_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """The ``view`` command."""
    view = commands.add_parser("view", help="explore a run in the browser, from its log")
    view.add_argument("run_dir", type=Path, help="a run folder written by 'mresim run'")
    add_server_flags(view)


def add_run_view_flags(run: argparse.ArgumentParser) -> None:
    """``--view`` and the server flags of ``mresim run``."""
    run.add_argument(
        "--view",
        action="store_true",
        help="watch and drive the run in the browser (it starts when a page connects)",
    )
    add_server_flags(run)


def check_run_flags(args: argparse.Namespace) -> None:
    """The server flags of ``mresim run`` need --view."""
    given = [f for f in VIEW_FLAGS if getattr(args, f, None) not in (None, False)]
    if given and not args.view:
        flag = "--" + given[0].replace("_", "-")
        raise MresimError(
            f"{flag} only applies with --view (mresim run SCENARIO --view {flag} ...)"
        )
