"""The ``scopelink`` command: one subcommand per module in this package.

Each subcommand module offers ``register(subparsers)``, which adds its parser and sets ``run`` (a
function taking the parsed namespace and returning the exit status) as the parser's default.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Callable, Sequence
from types import ModuleType

from scopelink import __version__
from scopelink.cli import (
    config_command,
    decode_command,
    emulate_command,
    goto_command,
    info_command,
    motion_commands,
    ports_command,
    serve_command,
    setup_commands,
    status_command,
)
from scopelink.cli.errors import CommandError

SUBCOMMANDS: tuple[ModuleType, ...] = (
    serve_command,
    emulate_command,
    decode_command,
    ports_command,
    info_command,
    status_command,
    goto_command,
    motion_commands,
    setup_commands,
    config_command,
)

EXIT_USAGE = 2


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
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
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in SUBCOMMANDS:
        module.register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.WARNING,
        format="%(asctime)s %(name)s %(message)s",
    )
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
