"""``move``, ``stop``, ``park``, ``unpark`` and ``guide``: the mount's hand controls (``track``,
which also follows moving targets, is ``track_command``; it uses :func:`tracking_mode_for`)."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
from typing import Final

from scopelink.astro import SIDEREAL_RATE_DEG_S
from scopelink.cli.commands import CommandParsers
from scopelink.cli.display import position_text
from scopelink.cli.errors import CommandError
from scopelink.cli.mount_session import run_on_mount
from scopelink.cli.options import add_device_arguments
from scopelink.cli.stopping import until_stopped
from scopelink.cli.targets import accept_negative_values
from scopelink.mount import (
    AlignmentMode,
    GuideDirection,
    Mount,
    MountAxis,
    ParkPosition,
    TrackingMode,
)
from scopelink.mount.slew_wait import slew_unless_stopped

__all__ = ["AXES", "parse_rate", "register"]

AXES: Final = {
    "primary": MountAxis.PRIMARY,
    "ra": MountAxis.PRIMARY,
    "az": MountAxis.PRIMARY,
    "secondary": MountAxis.SECONDARY,
    "dec": MountAxis.SECONDARY,
    "alt": MountAxis.SECONDARY,
}
"""Axis names: RA and azimuth are the primary axis, Dec and altitude the secondary."""

_PARK_TIMEOUT_S: Final = 600.0
_GUIDE_END_MARGIN_S: Final = 5.0


def _add(
    commands: CommandParsers, name: str, *, description: str, examples: str
) -> argparse.ArgumentParser:
    return commands.parser(
        name,
        description=description,
        epilog="examples:\n" + examples,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )


def register(commands: CommandParsers) -> None:
    move = _add(
        commands,
        "move",
        description=(
            "Turn AXIS (ra/az = primary, dec/alt = secondary) at RATE: degrees per second, "
            "signed (the sign is the direction the axis turns), or a multiple of the sidereal "
            "rate with an x suffix (16x). The axis stops on Ctrl-C or after --for seconds."
        ),
        examples=(
            "  scopelink move ra 2                 2°/s until Ctrl-C\n"
            "  scopelink move dec -16x --for 5     16x sidereal the other way, for 5 s\n"
        ),
    )
    move.add_argument("axis", choices=sorted(AXES), metavar="AXIS", help="ra|dec|az|alt|...")
    move.add_argument("rate", type=str, metavar="RATE", help="°/s (signed), or Nx sidereal")
    move.add_argument("--for", dest="seconds", type=float, metavar="S", help="stop after S s")
    add_device_arguments(move)
    accept_negative_values(move)
    move.set_defaults(run=_run_move)

    stop = _add(
        commands,
        "stop",
        description="Abort any slew and stop both axes. Tracking keeps its setting where the "
        "protocol allows.",
        examples=("  scopelink stop\n"),
    )
    add_device_arguments(stop)
    stop.set_defaults(run=_run_stop)

    park = _add(
        commands,
        "park",
        description="Park: slew to the park position, stop tracking, refuse motion until "
        "'scopelink unpark'. Waits for the slew (Ctrl-C stops the mount). Once parked, where "
        "the mount is goes on record, so that 'scopelink unpark' can resume after a power "
        "cycle without a new alignment (docs/parking.md).",
        examples=(
            "  scopelink park\n  scopelink park --no-wait\n  scopelink park --at 30,200\n"
            "  scopelink park --axes=-30,60     (SynScan: axis positions, by slow goto)\n"
        ),
    )
    park.add_argument("--no-wait", action="store_true", help="return once the slew has started")
    where = park.add_mutually_exclusive_group()
    where.add_argument(
        "--at",
        type=_two_numbers,
        metavar="ALT,AZ",
        help="park at this observed altitude and azimuth (degrees) instead of the default",
    )
    where.add_argument(
        "--axes",
        type=_two_numbers,
        metavar="P,S",
        help="SynScan: park at these axis positions (degrees; docs/parking.md)",
    )
    accept_negative_values(park)
    add_device_arguments(park)
    park.set_defaults(run=_run_park)

    unpark = _add(
        commands,
        "unpark",
        description="Unpark: the mount accepts motion commands again. A SynScan hand control "
        "that was switched off and on while parked gets its axis positions back from the "
        "park record first, so gotos land without a new alignment (docs/parking.md).",
        examples=("  scopelink unpark && scopelink track on\n"),
    )
    add_device_arguments(unpark)
    unpark.set_defaults(run=_run_unpark)

    guide = _add(
        commands,
        "guide",
        description="Nudge the mount at the guide rate towards DIRECTION for MS milliseconds "
        "(0-60000) and wait for the pulse to end.",
        examples=("  scopelink guide north 500\n  scopelink guide w 1200\n"),
    )
    guide.add_argument("direction", metavar="DIRECTION", help="north|south|east|west (or n/s/e/w)")
    guide.add_argument("milliseconds", type=int, metavar="MS", help="pulse length in ms")
    add_device_arguments(guide)
    guide.set_defaults(run=_run_guide)


# --- move and stop ---------------------------------------------------------------------------


def parse_rate(text: str) -> float:
    """Degrees per second from ``"2"``, ``"-0.5"``, or sidereal multiples ``"16x"``, ``"-800x"``."""
    cleaned = text.strip().lower()
    try:
        if cleaned.endswith("x"):
            return float(cleaned[:-1]) * SIDEREAL_RATE_DEG_S
        return float(cleaned)
    except ValueError:
        raise CommandError(
            f"cannot read the rate {text!r}", "give degrees per second (2, -0.5) or 16x sidereal"
        ) from None


def _run_move(args: argparse.Namespace) -> int:
    axis = AXES[args.axis]
    rate = parse_rate(args.rate)
    if args.seconds is not None and not args.seconds > 0:
        raise CommandError(f"--for must be positive, not {args.seconds}")

    async def body(mount: Mount) -> int:
        async with until_stopped() as stop:
            await mount.move_axis(axis, rate)
            try:
                until = "until Ctrl-C" if args.seconds is None else f"for {args.seconds:g} s"
                print(f"moving the {axis.name.lower()} axis at {rate:+.4f}°/s {until}", flush=True)
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(stop.wait(), args.seconds)
            finally:
                await mount.move_axis(axis, 0.0)
        state = await mount.refresh()
        print(f"stopped at {position_text(state)}")
        return 0

    return run_on_mount(args, body)


def _run_stop(args: argparse.Namespace) -> int:
    async def body(mount: Mount) -> int:
        await mount.abort()
        state = await mount.refresh()
        print(f"stopped at {position_text(state)}")
        return 0

    return run_on_mount(args, body)


# --- tracking ----------------------------------------------------------------------------------


def tracking_mode_for(mount: Mount, word: str) -> TrackingMode:
    """The mode ``word`` names; ``on`` is sidereal, or altaz on an alt-az mount without it."""
    if word != "on":
        return TrackingMode(word)
    modes = mount.capabilities.tracking_modes
    altaz = mount.capabilities.alignment_mode is AlignmentMode.ALT_AZ
    preferred = (
        (TrackingMode.ALT_AZ, TrackingMode.SIDEREAL)
        if altaz
        else (TrackingMode.SIDEREAL, TrackingMode.ALT_AZ)
    )
    for mode in preferred:
        if mode in modes:
            return mode
    raise CommandError("this mount cannot track", "'scopelink info' shows what it can do")


# --- park ------------------------------------------------------------------------------------


def _two_numbers(text: str) -> tuple[float, float]:
    try:
        first, second = (float(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not two numbers like 30,200") from None
    return first, second


def _choose_park(mount: Mount, args: argparse.Namespace) -> None:
    """``--at`` / ``--axes``: the park position for this park (checked like any other)."""
    if args.at is not None:
        alt, az = args.at
        mount.park_position = ParkPosition(alt, az % 360.0)
    elif args.axes is not None:
        at_axes = getattr(mount, "park_position_at_axes", None)
        if at_axes is None:
            raise CommandError("this mount cannot park at axis positions", "use --at ALT,AZ")
        mount.park_position = at_axes(*args.axes)


def _run_park(args: argparse.Namespace) -> int:
    async def body(mount: Mount) -> int:
        _choose_park(mount, args)
        async with until_stopped() as stop:
            await mount.park()
            if args.no_wait:
                print("parking")
                return 0
            state = await slew_unless_stopped(mount, stop, _PARK_TIMEOUT_S)
            if state is None:
                print("park interrupted: the mount was stopped")
                return 130
        print(f"parked at {position_text(state)}")
        return 0

    return run_on_mount(args, body)


def _run_unpark(args: argparse.Namespace) -> int:
    async def body(mount: Mount) -> int:
        resume = await mount.unpark()
        print(f"unparked: {resume.message}")
        return 0

    return run_on_mount(args, body)


# --- guide -----------------------------------------------------------------------------------

_DIRECTIONS: Final = {
    **{direction.value: direction for direction in GuideDirection},
    **{direction.value[0]: direction for direction in GuideDirection},
}


def _run_guide(args: argparse.Namespace) -> int:
    direction = _DIRECTIONS.get(args.direction.strip().lower())
    if direction is None:
        raise CommandError(
            f"unknown guide direction {args.direction!r}", "give north, south, east or west"
        )

    async def body(mount: Mount) -> int:
        await mount.pulse_guide(direction, args.milliseconds)
        # The driver ends the pulse itself; leaving early would cut it short on disconnect.
        await asyncio.sleep(args.milliseconds / 1000.0)
        await mount.wait_for(
            lambda state: not state.pulse_guiding,
            timeout_s=_GUIDE_END_MARGIN_S + args.milliseconds / 1000.0,
        )
        print(f"guided {direction.value} for {args.milliseconds} ms")
        return 0

    return run_on_mount(args, body)
