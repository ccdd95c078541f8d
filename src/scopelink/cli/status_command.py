"""``scopelink status [--watch]``: where the mount points and what it is doing.

Its options only: ``scopelink status --help`` loads no numpy or mount code; what it runs is in
:mod:`scopelink.cli.status_view`, imported by :func:`run` (docs/cli.md, "Start-up").
"""

from __future__ import annotations

import argparse

from scopelink.cli.commands import CommandParsers
from scopelink.cli.errors import CommandError
from scopelink.cli.options import add_device_arguments

__all__ = ["register", "run"]

_EXAMPLES = """\
examples:
  scopelink status --device synscan:/dev/ttyUSB0
  scopelink status --watch                  live table until Ctrl-C
  scopelink status --watch --json           one JSON line a second, for scripts
"""


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "status",
        description=(
            "Read the mount and show RA/Dec (J2000 and of date), Alt/Az, pier side, slewing, "
            "tracking and parked. With --watch the table stays live until Ctrl-C."
        ),
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("-w", "--watch", action="store_true", help="keep updating until Ctrl-C")
    parser.add_argument(
        "--interval",
        type=float,
        default=1.0,
        metavar="S",
        help="with --watch: show a new state at most every S seconds (default 1; the mount is "
        "polled as fast as its link allows)",
    )
    parser.add_argument("--json", action="store_true", help="JSON instead of a table")
    add_device_arguments(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if not args.interval > 0:
        raise CommandError(f"--interval must be positive, not {args.interval}")
    from scopelink.cli.status_view import show_status  # noqa: PLC0415 - heavy: only to run

    return show_status(args)
