"""``scopelink track``: tracking on, off or a mode, or follow a moving target (the Moon, a planet,
the Sun, a comet or asteroid from its elements, a satellite from its TLE) with a live view of the
tracking error until Ctrl-C (docs/cli.md, docs/tracking.md)."""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

from rich.console import Console
from rich.live import Live
from rich.text import Text

from scopelink.astro.targets import (
    MovingTarget,
    TargetError,
    orbit_target,
    satellite_target,
    solar_system_target,
)
from scopelink.cli.commands import CommandParsers
from scopelink.cli.errors import CommandError
from scopelink.cli.mount_session import run_on_mount
from scopelink.cli.options import add_device_arguments
from scopelink.cli.stopping import until_stopped
from scopelink.mount import Mount, TrackingMode
from scopelink.mount.follow import (
    MAX_DURATION_S,
    MAX_INTERVAL_S,
    FollowReport,
    TargetFollower,
)

__all__ = ["TrackDisplay", "follow", "make_target", "register", "run_track"]

MODE_WORDS = ("on", *(mode.value for mode in TrackingMode))
"""``track on|off|MODE``: set tracking, as before targets were added."""

BODIES = ("sun", "moon", "mercury", "venus", "mars", "jupiter", "saturn", "uranus", "neptune")
"""The solar-system bodies ``track`` follows by name (and ``pluto``)."""

KIND_WORDS = ("comet", "asteroid", "satellite")
"""``track comet NAME --elements FILE``, ``track asteroid ...``, ``track satellite NAME --tle``."""

_EXAMPLES = """\
examples:
  scopelink track on                                    sidereal (alt-az on an alt-az mount)
  scopelink track lunar                                 a named rate; 'off' stops tracking
  scopelink track moon                                  follow the Moon until Ctrl-C
  scopelink track jupiter --duration 600                ... Jupiter for 10 minutes
  scopelink track comet "C/2023 A3" --elements CometEls.txt
  scopelink track satellite ISS --tle stations.txt      its next pass, met ahead of it

Following: a goto to the target, then custom tracking rates from its ephemeris, corrected from
the mount's position; the live view shows the tracking error. Ctrl-C sets the rates back to zero
(the mount tracks at the sidereal rate). The Sun is refused while Sun avoidance is on.
"""


class _What(argparse.Action):
    """Check the first word (a mode, a body, or a kind of target) while parsing, so a typo gets
    the usage line and a suggestion like any invalid choice."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: str | Sequence[Any] | None,
        option_string: str | None = None,
    ) -> None:
        words = [str(v) for v in (values or [])]
        first = words[0].lower() if words else ""
        choices = (*MODE_WORDS, *BODIES, "pluto", *KIND_WORDS)
        if first not in choices:
            listed = ", ".join(f"'{c}'" for c in choices)
            parser.error(f"argument WHAT: invalid choice: '{words[0]}' (choose from {listed})")
        if first in MODE_WORDS + BODIES + ("pluto",) and len(words) > 1:
            parser.error(f"'track {first}' takes no more words (got {' '.join(words[1:])!r})")
        if first in KIND_WORDS and len(words) < 2:
            parser.error(f"'track {first}' needs a name, e.g. track {first} NAME")
        setattr(namespace, self.dest, words)


def register(commands: CommandParsers) -> None:
    track = commands.parser(
        "track",
        description=(
            "Set tracking ('on', 'off' or a mode this mount supports), or follow a moving target: "
            "the Moon, a planet, the Sun (with Sun avoidance off), a comet or asteroid from an "
            "elements file (MPC one-line or XEphem), a satellite from a TLE file."
        ),
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    track.add_argument(
        "what",
        nargs="+",
        action=_What,
        metavar="WHAT",
        help="on|off|MODE, or moon|sun|PLANET, or comet|asteroid|satellite NAME",
    )
    track.add_argument("--elements", type=Path, metavar="FILE", help="orbital elements file")
    track.add_argument("--tle", type=Path, metavar="FILE", help="TLE file (2- or 3-line)")
    track.add_argument(
        "--duration", type=float, metavar="S", help="stop following after S s of the mount's clock"
    )
    track.add_argument(
        "--interval",
        type=float,
        metavar="S",
        help="seconds between rate updates (default 30; 1 for a satellite)",
    )
    add_device_arguments(track)
    track.set_defaults(run=run_track)


def run_track(args: argparse.Namespace) -> int:
    first = args.what[0].lower()
    if first in MODE_WORDS:
        return _run_mode(args, first)
    for value, name, most in (
        (args.duration, "--duration", MAX_DURATION_S),
        (args.interval, "--interval", MAX_INTERVAL_S),
    ):
        if value is not None and not (math.isfinite(value) and 0.0 < value <= most):
            raise CommandError(
                f"{name} must be a number of seconds in (0, {most:g}], not {value:g}"
            )
    if first in ("comet", "asteroid") and args.elements is None:
        raise CommandError(
            f"track {first} needs --elements FILE",
            "an MPC one-line file (CometEls.txt, MPCORB.DAT lines) or XEphem .edb lines",
        )
    if first == "satellite" and args.tle is None:
        raise CommandError("track satellite needs --tle FILE", "a 2- or 3-line TLE file")

    async def body(mount: Mount) -> int:
        return await follow(mount, args)

    return run_on_mount(args, body, long_running=True)  # hours of polls: on uvloop


def _run_mode(args: argparse.Namespace, word: str) -> int:
    from scopelink.cli.motion_commands import tracking_mode_for  # noqa: PLC0415

    async def body(mount: Mount) -> int:
        mode = tracking_mode_for(mount, word)
        await mount.set_tracking(mode)
        state = await mount.refresh()
        print(f"tracking: {state.tracking.value}")
        return 0

    return run_on_mount(args, body)


class TrackDisplay:
    """The tracking error live on a terminal; elsewhere a line a second on stderr."""

    def __init__(self, label: str) -> None:
        self._label = label
        self._console = Console(stderr=True, highlight=False)
        self._live: Live | None = None
        self._printed_at = 0.0

    def __enter__(self) -> TrackDisplay:
        if self._console.is_terminal:
            self._live = Live(Text(self._label), console=self._console, transient=True)
            self._live.start()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._live is not None:
            self._live.stop()

    def show(self, phase: str, error_arcsec: float | None, ra_rate: float, dec_rate: float) -> None:
        error = "" if error_arcsec is None else f", error {_arcsec(error_arcsec)}"
        rates = (
            f" (rates RA {ra_rate:+.3f}″/s, Dec {dec_rate:+.3f}″/s)" if phase == "following" else ""
        )
        line = f"{self._label}: {phase}{error}{rates}"
        if self._live is not None:
            self._live.update(Text(line + "  (Ctrl-C stops)"))
            return
        now = time.monotonic()
        if now - self._printed_at >= 1.0:
            self._printed_at = now
            print(line, file=sys.stderr, flush=True)


def _arcsec(value: float) -> str:
    if value >= 3600.0:
        return f"{value / 3600.0:.2f}°"
    if value >= 60.0:
        return f"{value / 60.0:.1f}′"
    return f"{value:.1f}″"


# --- following a target ------------------------------------------------------------------


def make_target(args: argparse.Namespace, mount: Mount) -> MovingTarget:
    """The target the words name, seen from the mount's site; one line on a bad file or name."""
    first, name = args.what[0].lower(), " ".join(args.what[1:])
    try:
        if first in ("comet", "asteroid"):
            return orbit_target(name, args.elements, mount.site)
        if first == "satellite":
            return satellite_target(name, args.tle, mount.site)
        return solar_system_target(first, mount.site)
    except TargetError as error:
        raise CommandError(str(error)) from None


async def follow(mount: Mount, args: argparse.Namespace) -> int:
    from scopelink.cli.serve_mount import ServeMount  # noqa: PLC0415

    served: object = mount  # run_on_mount gives a ServeMount in a Mount's place
    if isinstance(served, ServeMount):  # the follower must run where the mount is driven
        raise served.cannot(
            "following",
            "the serve follows the Moon, a planet or the Sun itself (POST /api/track on its "
            "dashboard, docs/dashboard.md); for any target, stop the serve and give "
            "--device DEVICE",
        )
    target = make_target(args, mount)
    with TrackDisplay(target.name) as display:

        def show(report: FollowReport) -> None:
            display.show(
                report.phase, report.error_arcsec, report.ra_rate_arcsec_s, report.dec_rate_arcsec_s
            )

        follower = TargetFollower(mount, target, interval_s=args.interval, on_report=show)
        try:
            plan = follower.check()  # refusals before anything moves, with the pass plan
        except TargetError as error:  # e.g. a TLE SGP4 cannot carry to tonight
            raise CommandError(str(error)) from None
        if plan is not None:
            print(
                f"{target.name}: pass {plan.rise:%H:%M:%S}-{plan.set:%H:%M:%S} UTC, culminating "
                f"at {plan.max_alt_deg:.0f}°; following from {plan.start:%H:%M:%S} UTC"
                + (f" ({plan.note})" if plan.note else ""),
                flush=True,
            )
        else:
            print(f"following {target.name} ({target.kind.value})", flush=True)
        async with until_stopped() as stop:
            try:
                result = await follower.run(stop=stop, duration_s=args.duration)
            except TargetError as error:
                raise CommandError(str(error)) from None
    if result.errors:
        span = (result.errors[-1][0] - result.errors[0][0]).total_seconds()
        worst = max(e for _, e in result.errors)
        print(
            f"followed {target.name} for {span:.0f} s: tracking error "
            f"{result.rms_arcsec():.1f}″ RMS, {worst:.1f}″ max; {result.reason}; "
            "rates back to zero",
            flush=True,
        )
    else:
        print(f"{target.name}: {result.reason or 'not followed'}", flush=True)
    return 0
