"""``scopelink status [--watch]``: where the mount points and what it is doing."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import time
from contextlib import aclosing

from rich.console import Console
from rich.live import Live

from scopelink.cli.commands import CommandParsers
from scopelink.cli.display import state_json, state_table
from scopelink.cli.errors import CommandError
from scopelink.cli.mount_session import add_device_arguments, run_on_mount
from scopelink.cli.options import until_stopped
from scopelink.mount import Mount, MountState

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

    async def body(mount: Mount) -> int:
        if not args.watch:
            _show_once(mount, await mount.refresh(), as_json=args.json)
            return 0
        async with until_stopped() as stop:
            watcher = asyncio.create_task(_watch(mount, args.interval, as_json=args.json))
            stopper = asyncio.create_task(stop.wait())
            done, _ = await asyncio.wait({watcher, stopper}, return_when=asyncio.FIRST_COMPLETED)
            for task in (watcher, stopper):
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
            if watcher in done:
                watcher.result()  # re-raise what ended the watch
        return 0

    return run_on_mount(args, body)


def _show_once(mount: Mount, state: MountState, *, as_json: bool) -> None:
    if as_json:
        print(json.dumps(state_json(state)), flush=True)
    else:
        Console(highlight=False).print(state_table(mount, state))


async def _watch(mount: Mount, interval_s: float, *, as_json: bool) -> None:
    console = Console(highlight=False)
    live_table = console.is_terminal and not as_json
    shown_at = -interval_s
    async with aclosing(mount.states()) as states:
        if not live_table:
            async for state in states:
                if time.monotonic() - shown_at >= interval_s:
                    shown_at = time.monotonic()
                    _show_once(mount, state, as_json=as_json)
            return
        with Live(state_table(mount, mount.state), console=console, auto_refresh=False) as live:
            async for state in states:
                if time.monotonic() - shown_at >= interval_s:
                    shown_at = time.monotonic()
                    live.update(state_table(mount, state), refresh=True)
