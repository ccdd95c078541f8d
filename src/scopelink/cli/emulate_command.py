"""``scopelink emulate DEVICE``: run an emulated device on a pty or a TCP port until Ctrl-C.

Devices live in :data:`EMULATORS` (name -> :class:`EmulatedDevice`); adding one is one entry.
Every device gets the common options (where to serve, pacing, faults, site, clock); its own
``add_arguments`` adds the rest, and its ``create`` builds the (not yet started) device.
"""

from __future__ import annotations

import argparse
import asyncio
import os
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path

from scopelink.astro import PierSide, Site
from scopelink.cli.commands import CommandParsers
from scopelink.cli.errors import CommandError
from scopelink.cli.mount_session import parse_site
from scopelink.cli.options import (
    add_site_and_clock_arguments,
    parse_host_port,
    positive_rate,
)
from scopelink.cli.stopping import until_stopped
from scopelink.links import LinkError, precise_event_loop
from scopelink.mount import Limits
from scopelink.protocol.synscan import Version, VersionDialect
from scopelink.servers.faults import Fault, FaultInjector, FaultSpecError
from scopelink.servers.hosting import SERIAL_9600_8N1, HostedDevice, WireSpeed
from scopelink.servers.ready import ready_json
from scopelink.servers.skytracker import SkyCommanderEmulator, SkyTrackerEmulator
from scopelink.servers.synscan import DEFAULT_FIRMWARE, Quirks, SynScanConfig, SynScanEmulator
from scopelink.sim import PRESETS, SKY_TRACKER, SimClock, SimulatedMount, geometry_for
from scopelink.sim.misalignment import Misalignment, parse_misalignment

__all__ = ["EMULATORS", "EmulatedDevice", "EmulatorOptions", "register", "run"]


@dataclass(frozen=True, slots=True)
class EmulatorOptions:
    """What every emulated device is given, from the common options."""

    faults: FaultInjector
    wire: WireSpeed | None
    site: Site
    clock: SimClock


@dataclass(frozen=True, slots=True)
class EmulatedDevice:
    """One entry of ``scopelink emulate``: its help line, its own options and its factory."""

    help: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    create: Callable[[argparse.Namespace, EmulatorOptions], Awaitable[HostedDevice]]


# --- SynScan ------------------------------------------------------------------------------------


def _add_synscan_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--mount",
        default="eq6",
        choices=sorted(
            name for name, model in PRESETS.items() if model.synscan_model_code is not None
        ),
        help="simulated mount preset (default eq6)",
    )
    parser.add_argument("--model", type=int, help="'m' model code (default: the preset's)")
    parser.add_argument(
        "--firmware",
        type=_version,
        default=DEFAULT_FIRMWARE,
        help="'V' firmware version, e.g. 4.39.05 (default); 3.36.2 for old firmware",
    )
    parser.add_argument(
        "--binary-version",
        action="store_true",
        help="answer 'V' with 3 binary bytes (old firmware)",
    )
    parser.add_argument("--unaligned", action="store_true", help="the hand control is not aligned")
    parser.add_argument(
        "--power-on-at",
        type=_az_alt,
        metavar="AZ,ALT",
        help="start as just switched on with the tube at this azimuth and altitude (degrees): "
        "the counters at their power-on values, not aligned (docs/parking.md)",
    )
    parser.add_argument(
        "--latency", type=float, default=0.0, metavar="S", help="delay every reply (0-5 s)"
    )
    parser.add_argument(
        "--sync-limit",
        type=float,
        default=Quirks().sync_limit_deg,
        metavar="DEG",
        help="ignore syncs further than this (default 7); 0 obeys every sync",
    )
    parser.add_argument(
        "--sticky-altaz-goto", action="store_true", help="'L' never clears after an Alt-Az goto"
    )
    parser.add_argument(
        "--resume-after-cancel", action="store_true", help="rate slews resume after 'M'"
    )
    parser.add_argument(
        "--passthrough-succeeds",
        action="store_true",
        help="unanswerable passthroughs answer '#' instead of the failed form",
    )
    parser.add_argument("--swapped-model", action="store_true", help="'m' answers '#' first")
    parser.add_argument(
        "--misalign",
        type=_misalignment,
        default=None,
        metavar="ZP1,ZP2,PAZ,PALT",
        help="misalign the simulated sky (degrees): axis zero points, polar axis (or base) "
        "error in azimuth and altitude (docs/pointing.md)",
    )


def _misalignment(text: str) -> Misalignment:
    try:
        return parse_misalignment(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _az_alt(text: str) -> tuple[float, float]:
    try:
        az, alt = (float(part) for part in text.split(","))
    except ValueError:
        message = f"{text!r} is not an azimuth,altitude like 180,45"
        raise argparse.ArgumentTypeError(message) from None
    if not (0.0 <= az < 360.0 and -90.0 <= alt <= 90.0):
        raise argparse.ArgumentTypeError(f"{text!r}: azimuth in [0, 360), altitude in [-90, 90]")
    return az, alt


def _version(text: str) -> Version:
    try:
        major, minor, patch = (int(part) for part in text.split("."))
        return Version(major, minor, patch)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a version like 4.39.05") from None


async def _create_synscan(args: argparse.Namespace, options: EmulatorOptions) -> HostedDevice:
    preset = PRESETS[args.mount]
    firmware: Version = args.firmware
    if args.binary_version:
        firmware = Version(
            firmware.major, firmware.minor, firmware.patch, VersionDialect.SYNSCAN_BINARY
        )
    quirks = Quirks(
        sync_limit_deg=args.sync_limit or None,
        sticky_altaz_goto=args.sticky_altaz_goto,
        resume_after_cancel=args.resume_after_cancel,
        failed_passthrough=not args.passthrough_succeeds,
        model_swapped=args.swapped_model,
    )
    model = args.model if args.model is not None else preset.synscan_model_code
    config = SynScanConfig(
        model=model or 0,
        firmware=firmware,
        aligned=not args.unaligned,
        latency_s=args.latency,
        quirks=quirks,
    )
    home = None
    if args.power_on_at is not None:  # the tube points there; the counters restart at power-on
        az, alt = args.power_on_at
        geometry = geometry_for(preset.alignment_mode, options.site.latitude_deg)
        home = geometry.to_axes(alt, az, PierSide.UNKNOWN)
    mount = SimulatedMount(
        preset,
        site=options.site,
        clock=options.clock,
        limits=_DEVICE_LIMITS,
        home=home,
        misalignment=args.misalign,
    )
    return SynScanEmulator(
        mount, config, faults=options.faults, wire=options.wire, cold_start=home is not None
    )


_DEVICE_LIMITS = Limits(sun_avoidance_deg=0.0)
"""An emulated device knows nothing of the Sun, as the real one: scopelink's side guards it."""

# --- Sky Tracker and Sky Commander ---------------------------------------------------------------


def _default_data_dir() -> Path:
    base = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return Path(base) / "scopelink"


def _add_sky_commander_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data-dir",
        type=Path,
        default=None,
        help="where non-volatile memory (objects, calibration) is kept "
        "(default $XDG_DATA_HOME/scopelink)",
    )


def _add_sky_tracker_arguments(parser: argparse.ArgumentParser) -> None:
    _add_sky_commander_arguments(parser)
    parser.add_argument(
        "--strict-line",
        action="store_true",
        help="lose characters sent faster than 8N2, as the real box's unbuffered port does",
    )


async def _create_sky_tracker(args: argparse.Namespace, options: EmulatorOptions) -> HostedDevice:
    mount = SimulatedMount(
        SKY_TRACKER, site=options.site, clock=options.clock, limits=_DEVICE_LIMITS
    )
    return SkyTrackerEmulator(
        mount,
        args.data_dir or _default_data_dir(),
        faults=options.faults,
        pace=options.wire is not None,
        strict_line=args.strict_line,
    )


async def _create_sky_commander(args: argparse.Namespace, options: EmulatorOptions) -> HostedDevice:
    mount = SimulatedMount(
        SKY_TRACKER, site=options.site, clock=options.clock, limits=_DEVICE_LIMITS
    )
    return SkyCommanderEmulator(
        mount,
        args.data_dir or _default_data_dir(),
        faults=options.faults,
        pace=options.wire is not None,
    )


EMULATORS: dict[str, EmulatedDevice] = {
    "synscan": EmulatedDevice(
        "a SynScan V4 hand control in front of a simulated mount",
        _add_synscan_arguments,
        _create_synscan,
    ),
    "skytracker": EmulatedDevice(
        "a Sky Tracker motor box with its Sky Commander on the bus, driving a simulated alt-az "
        "mount",
        _add_sky_tracker_arguments,
        _create_sky_tracker,
    ),
    "skycommander": EmulatedDevice(
        "a Sky Commander (digital setting circles) alone on its port, reading a simulated "
        "alt-az mount",
        _add_sky_commander_arguments,
        _create_sky_commander,
    ),
}
"""Emulated devices by name; each one is a ``scopelink emulate NAME`` subcommand."""


# --- the command ----------------------------------------------------------------------------------


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "emulate",
        description="Run an emulated device until Ctrl-C. It prints where clients connect.",
    )
    devices = parser.add_subparsers(dest="device", metavar="DEVICE", required=True)
    for name, device in EMULATORS.items():
        device_parser = devices.add_parser(name, help=device.help, description=device.help)
        _add_common_arguments(device_parser)
        device.add_arguments(device_parser)
        device_parser.set_defaults(run=run)


def _add_common_arguments(parser: argparse.ArgumentParser) -> None:
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--pty",
        nargs="?",
        const="",
        metavar="SYMLINK",
        help="serve a pseudo-terminal (default), optionally also reachable as SYMLINK",
    )
    where.add_argument("--tcp", metavar="HOST:PORT", help="listen on TCP (port 0 picks one)")
    parser.add_argument(
        "--no-pacing", action="store_true", help="send replies at once instead of at 9600 baud"
    )
    parser.add_argument(
        "--fault",
        action="append",
        default=[],
        metavar="SPEC",
        help="inject a fault: COMMAND:KIND[=SECONDS][:once|:always|:times=N][:p=P], e.g. "
        "e:drop, any:delay=6:p=0.1 (kinds: drop short malformed delay slow stall halt close)",
    )
    parser.add_argument("--seed", type=int, help="seed of probabilistic faults")
    parser.add_argument(
        "--ready-json", action="store_true", help="say where it listens as one JSON line"
    )
    parser.add_argument(
        "--replay",
        metavar="FILE",
        help="answer from a recording ('scopelink record'), reporting each divergence on stderr",
    )
    add_site_and_clock_arguments(parser)


def run(args: argparse.Namespace) -> int:
    try:
        faults = FaultInjector((Fault.parse(spec) for spec in args.fault), seed=args.seed)
    except FaultSpecError as error:
        raise CommandError(str(error)) from None
    options = EmulatorOptions(
        faults=faults,
        wire=None if args.no_pacing else SERIAL_9600_8N1,
        site=parse_site(args.site),
        clock=SimClock(rate=positive_rate(args.clock_rate)),
    )
    # Paced replies keep time to ~0.1 ms on this loop (epoll would round every wait up to 1 ms).
    with asyncio.Runner(loop_factory=precise_event_loop) as runner:
        return runner.run(_serve(args, options))


async def _serve(args: argparse.Namespace, options: EmulatorOptions) -> int:
    device: HostedDevice
    if args.replay:
        from scopelink.cli.replay_device import replay_device  # noqa: PLC0415 - if asked for

        device = replay_device(args.replay, args.device, options.wire)
    else:
        device = await EMULATORS[args.device].create(args, options)
    try:
        async with until_stopped() as stop, device:
            if args.tcp is not None:
                await device.on_tcp(*parse_host_port(args.tcp, "--tcp"))
                ready = f"{args.device} emulator listening on {device.address}"
            else:
                ready = f"{args.device} emulator on {await device.on_pty(args.pty or None)}"
            print(ready_json(args.device, device) if args.ready_json else ready, flush=True)
            await stop.wait()
    except LinkError as error:
        raise CommandError(str(error)) from None
    return 0
