"""``scopelink goto TARGET`` (progress; Ctrl-C aborts the slew) and ``scopelink sync TARGET``."""

from __future__ import annotations

import argparse
import asyncio
import sys
import time
from types import TracebackType

from rich.console import Console
from rich.progress import BarColumn, Progress, TaskID, TextColumn

from scopelink.astro import format_degrees, format_hours
from scopelink.astro.catalog import lookup
from scopelink.cli.commands import CommandParsers
from scopelink.cli.display import position_text
from scopelink.cli.errors import CommandError
from scopelink.cli.mount_session import run_on_mount
from scopelink.cli.options import add_device_arguments
from scopelink.cli.stopping import until_stopped
from scopelink.cli.targets import AltAz, Named, accept_negative_values, parse_target
from scopelink.mount import Mount, SlewProgress
from scopelink.mount.slew_wait import slew_unless_stopped

__all__ = ["EXIT_INTERRUPTED", "SlewDisplay", "register", "run_goto", "run_sync"]

_STALE_POSITION_S = 3.0
"""A slew whose reported position has not changed for this long is flagged as not updating."""

EXIT_INTERRUPTED = 130
"""Ctrl-C: the shell's convention (128 + SIGINT)."""

DEFAULT_SLEW_TIMEOUT_S = 600.0
"""The longest slew of a SynScan mount at 3.4°/s takes under two minutes; a slew still running
after ten is stuck, and is aborted."""

_GOTO_EXAMPLES = """\
examples:
  scopelink goto M31                          a catalogue name (Messier, NGC, IC, stars, planets)
  scopelink goto "HIP 91262"
  scopelink goto 05:35:17 -05:23:28           J2000 RA and Dec (hours, degrees)
  scopelink goto "5.5883 -5.391"
  scopelink goto --altaz 45 180               observed altitude and azimuth (degrees)
  scopelink goto Jupiter --no-wait            start the slew and return

Ctrl-C during the slew stops the mount.
"""

_SYNC_EXAMPLES = """\
examples:
  scopelink sync Vega                the mount is pointing at Vega
  scopelink sync 18:36:56 +38:47:01  ... at this J2000 RA and Dec
"""


def register(commands: CommandParsers) -> None:
    goto = commands.parser(
        "goto",
        description=(
            "Slew to TARGET: a name from the offline catalogue, or J2000 'RA DEC' (hours and "
            "degrees, decimal or sexagesimal), or with --altaz 'ALT AZ' in degrees. Shows the "
            "distance to go and an arrival estimate; Ctrl-C stops the mount. Targets below the "
            "configured horizon are refused before anything is sent."
        ),
        epilog=_GOTO_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    goto.add_argument("target", nargs="+", metavar="TARGET", help="name, or RA DEC, or ALT AZ")
    goto.add_argument("--altaz", action="store_true", help="TARGET is altitude and azimuth")
    goto.add_argument("--no-wait", action="store_true", help="return once the slew has started")
    goto.add_argument(
        "--slew-timeout",
        type=float,
        default=DEFAULT_SLEW_TIMEOUT_S,
        metavar="S",
        help=f"abort a slew still running after S seconds (default {DEFAULT_SLEW_TIMEOUT_S:g})",
    )
    add_device_arguments(goto)
    accept_negative_values(goto)
    goto.set_defaults(run=run_goto)

    sync = commands.parser(
        "sync",
        description="Sync: the mount is pointing at TARGET (a name, or J2000 'RA DEC').",
        epilog=_SYNC_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sync.add_argument("target", nargs="+", metavar="TARGET", help="name, or RA DEC")
    add_device_arguments(sync)
    accept_negative_values(sync)
    sync.set_defaults(run=run_sync)


def _radec_text(ra_hours: float, dec_deg: float) -> str:
    return f"RA {format_hours(ra_hours)} Dec {format_degrees(dec_deg)}"


def run_goto(args: argparse.Namespace) -> int:
    target = parse_target(args.target, altaz=args.altaz)
    if not args.slew_timeout > 0:
        raise CommandError(f"--slew-timeout must be positive, not {args.slew_timeout}")

    async def body(mount: Mount) -> int:
        # Ctrl-C is caught from before the goto is sent, so one pressed while it starts still
        # stops the mount once the slew is under way.
        async with until_stopped() as stop:
            if isinstance(target, Named):
                found = await mount.goto_object(target.name)
                label = found.name
                where = _radec_text(found.ra_hours, found.dec_deg)
                print(f"slewing to {found.name}: {where} (J2000)", flush=True)
            elif isinstance(target, AltAz):
                await mount.goto_horizontal(target.alt_deg, target.az_deg)
                label = f"Alt {target.alt_deg:g}° Az {target.az_deg:g}°"
                print(f"slewing to {label}", flush=True)
            else:
                await mount.goto_equatorial(target.ra_hours, target.dec_deg)
                label = _radec_text(target.ra_hours, target.dec_deg)
                print(f"slewing to {label} (J2000)", flush=True)
            if args.no_wait:
                return 0
            return await _follow_slew(mount, label, args.slew_timeout, stop)

    return run_on_mount(args, body)


async def _follow_slew(mount: Mount, label: str, timeout_s: float, stop: asyncio.Event) -> int:
    """Show progress until the slew ends; ``stop`` (Ctrl-C) or a timeout aborts it."""
    try:
        with SlewDisplay(label) as display:
            ended = await slew_unless_stopped(mount, stop, timeout_s, display.update)
    except TimeoutError:
        await mount.abort()
        raise CommandError(
            f"the slew did not end within {timeout_s:g} s: the mount was stopped",
            "check the mount for obstructions; raise --slew-timeout for very slow mounts",
        ) from None
    if ended is None:
        state = await mount.refresh()
        print(f"slew aborted; the mount stopped at {position_text(state)}", flush=True)
        return EXIT_INTERRUPTED
    state = ended
    print(f"arrived: {position_text(state)}", flush=True)
    return 0


class SlewDisplay:
    """A progress bar on a terminal; elsewhere a line a second on stderr (logs, scripts)."""

    def __init__(self, label: str, stale_after_s: float = _STALE_POSITION_S) -> None:
        self._label = label
        self._stale_after_s = stale_after_s
        self._console = Console(stderr=True, highlight=False)
        self._progress: Progress | None = None
        self._task: TaskID | None = None
        self._start_distance: float | None = None
        self._printed_at = 0.0
        self._last_distance: float | None = None
        self._changed_at = time.monotonic()

    def __enter__(self) -> SlewDisplay:
        if self._console.is_terminal:
            self._progress = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                TextColumn("{task.fields[distance]}"),
                TextColumn("{task.fields[eta]}"),
                console=self._console,
                transient=True,
            )
            self._progress.start()
            self._task = self._progress.add_task(self._label, total=None, distance="", eta="")
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._progress is not None:
            self._progress.stop()

    def update(self, progress: SlewProgress) -> None:
        distance, eta = progress.distance_deg, progress.eta_s
        distance_text = "" if distance is None else f"{distance:.2f}° to go"
        now = time.monotonic()
        if distance != self._last_distance:
            self._last_distance, self._changed_at = distance, now
        elif progress.state.slewing and now - self._changed_at > self._stale_after_s:
            # A Sky Tracker refuses its bus during a GOTO, so no position is read until it ends.
            distance_text += " (position not updating)"
        eta_text = "" if eta is None else f"ETA {_duration(eta)}"
        if self._progress is not None and self._task is not None:
            if distance is not None and self._start_distance is None:
                self._start_distance = max(distance, 1e-6)
            total = self._start_distance
            done = None if total is None or distance is None else max(0.0, total - distance)
            self._progress.update(
                self._task, total=total, completed=done, distance=distance_text, eta=eta_text
            )
            return
        if now - self._printed_at >= 1.0:
            self._printed_at = now
            parts = ", ".join(part for part in (distance_text, eta_text) if part) or "slewing"
            print(f"{self._label}: {parts}", file=sys.stderr, flush=True)


def _duration(seconds: float) -> str:
    whole = round(seconds)
    return f"{whole // 60}:{whole % 60:02d}" if whole >= 60 else f"{whole} s"


def run_sync(args: argparse.Namespace) -> int:
    target = parse_target(args.target)
    if isinstance(target, AltAz):  # pragma: no cover - parse_target without altaz never says so
        raise CommandError("sync takes RA and Dec")

    async def body(mount: Mount) -> int:
        if isinstance(target, Named):
            found = lookup(target.name, mount.now(), mount.site)
            ra, dec, label = found.ra_hours, found.dec_deg, found.name
        else:
            ra, dec = target.ra_hours, target.dec_deg
            label = _radec_text(ra, dec)
        await mount.sync_equatorial(ra, dec)
        state = await mount.refresh()
        print(f"synced on {label}; the mount reads {position_text(state)}")
        return 0

    return run_on_mount(args, body)
