"""What ``scopelink status`` runs once its options are parsed (:mod:`.status_command`)."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import time
from contextlib import aclosing

from rich.console import Console
from rich.live import Live

from scopelink.cli.display import state_json, state_table
from scopelink.cli.mount_session import run_on_mount
from scopelink.cli.stopping import until_stopped
from scopelink.mount import Mount, MountState

__all__ = ["show_status"]


def show_status(args: argparse.Namespace) -> int:
    """Read the mount once, or watch it until Ctrl-C, as ``args`` (checked) say."""

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
