"""Option values shared by several subcommands, parsed with errors that say what to type."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import signal
from collections.abc import AsyncIterator

from scopelink.astro import Site
from scopelink.cli.errors import CommandError

DEFAULT_SITE = "51.4779,-0.0015"
"""Greenwich: a neutral default until the user configures a site."""


def add_site_and_clock_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--site",
        default=DEFAULT_SITE,
        metavar="LAT,LON",
        help="site latitude and east longitude in degrees (default Greenwich)",
    )
    parser.add_argument(
        "--clock-rate", type=float, default=1.0, metavar="X", help="simulated time speed (1 = real)"
    )


def parse_site(text: str) -> Site:
    try:
        latitude, longitude = (float(part) for part in text.split(","))
        return Site(latitude, longitude)
    except ValueError as error:
        raise CommandError(f"bad --site {text!r}: {error}", "give LAT,LON like 40.4,-3.7") from None


def positive_rate(rate: float) -> float:
    if not rate > 0:
        raise CommandError(f"--clock-rate must be positive, not {rate}")
    return rate


def parse_host_port(text: str, option: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit():
        raise CommandError(f"bad {option} {text!r}", "give HOST:PORT, e.g. 127.0.0.1:0")
    return host, int(port)


@contextlib.asynccontextmanager
async def until_stopped() -> AsyncIterator[asyncio.Event]:
    """An event set by Ctrl-C or SIGTERM, so a long-running command can shut down cleanly."""
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    previous: dict[int, object] = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        try:
            loop.add_signal_handler(signum, stop.set)
        except NotImplementedError:
            # Windows event loops have no signal handlers: a plain handler wakes the loop.
            previous[signum] = signal.signal(signum, lambda *_: loop.call_soon_threadsafe(stop.set))
    try:
        yield stop
    finally:
        for signum in (signal.SIGINT, signal.SIGTERM):
            if signum in previous:
                signal.signal(signum, previous[signum])  # type: ignore[arg-type]
                continue
            with contextlib.suppress(ValueError, NotImplementedError):
                loop.remove_signal_handler(signum)
