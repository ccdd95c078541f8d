"""The ``scopelink`` command: the subcommands of :mod:`scopelink.cli.commands`.

Only this module, :mod:`~scopelink.cli.commands` and :mod:`~scopelink.cli.errors` are imported
before the command line is parsed; a subcommand's module (and what it needs: numpy, the servers,
aiohttp) is imported when that subcommand is used (docs/cli.md, "Start-up").
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

from scopelink import __version__
from scopelink.cli.commands import SuggestingParser, add_commands
from scopelink.cli.errors import CommandError
from scopelink.cli.log_lines import configure_logging

EXIT_USAGE = 2


def build_parser() -> SuggestingParser:
    parser = SuggestingParser(
        prog="scopelink",
        description="Control, emulate and bridge SynScan and Sky Tracker telescope mounts.",
    )
    parser.add_argument("--version", action="version", version=f"scopelink {__version__}")
    parser.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="more detail; -v shows the byte trace of every link",
    )
    parser.commands = add_commands(parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args, extras = parser.parse_known_args(argv)
    if extras:  # a mistyped option: the command's own usage, and the option meant
        command = getattr(args, "command", None)
        owner = parser.commands.get(command, parser) if command else parser
        owner.refuse_unknown_options(extras)
    configure_logging(args.verbose)
    run: Callable[[argparse.Namespace], int] | None = getattr(args, "run", None)
    if run is None:
        parser.print_help()
        return EXIT_USAGE
    try:
        return run(args)
    except CommandError as error:
        print(f"scopelink {args.command}: {error}", file=sys.stderr)
        if error.hint:
            print(f"  hint: {error.hint}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
