"""What every device command shares: its options, the config merge, and one run on a mount.

A device command declares its options with :func:`scopelink.cli.options.add_device_arguments`
and runs its body with :func:`run_on_mount`, which reads the config, opens the device, calls the
body with the connected mount, disconnects, and turns every expected failure into one
:class:`CommandError` line.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import cast

from rich.console import Console

from scopelink.astro import Site
from scopelink.astro.catalog import EphemerisRangeError, UnknownObjectError
from scopelink.cli.config import CONFIG_ENV_VAR, Config, ConfigError, config_path, load_config
from scopelink.cli.errors import CommandError
from scopelink.cli.options import positive_rate
from scopelink.drivers.open import (
    EXAMPLES,
    SERVE_KIND,
    DeviceOpenError,
    DeviceSpec,
    open_mount,
    parse_device,
)
from scopelink.links import (
    EVENT_LOOP_CHOICES,
    EventLoopChoice,
    EventLoopChoiceError,
    LinkError,
    choose_event_loop,
)
from scopelink.links.serial import PORT_BUSY
from scopelink.links.trace import trace_logger
from scopelink.mount import (
    LimitError,
    Limits,
    Mount,
    MountError,
    NotSupportedError,
    ParkedError,
    SunAvoidanceError,
)
from scopelink.mount.memory import DeviceMemory
from scopelink.mount.pointing import device_key

__all__ = [
    "DeviceCommand",
    "mount_error",
    "open_device",
    "parse_site",
    "read_config",
    "run_on_mount",
]

_log = logging.getLogger(__name__)

_HINTS: dict[type[MountError], str] = {
    SunAvoidanceError: "the zone around the Sun is limits.sun_avoidance_deg in the config file",
    LimitError: "the horizon and limits are set in the config file ([horizon], [limits])",
    ParkedError: "run 'scopelink unpark' first",
    NotSupportedError: "'scopelink info' shows what this mount can do",
}


def read_config() -> Config:
    """The settings file, or a :class:`CommandError` naming the file, the key and the problem."""
    try:
        return load_config()
    except ConfigError as error:
        raise CommandError(
            str(error), f"fix the file, or point {CONFIG_ENV_VAR} at another one"
        ) from None


@dataclass(frozen=True, slots=True)
class DeviceCommand:
    """The merged settings of one device command: flags over the config file."""

    device: DeviceSpec
    site: Site
    config: Config
    clock_rate: float
    timeout_s: float | None
    site_given: bool = False
    """The site is to be sent (``scopelink site``): a serve's mount is then given this one."""

    @classmethod
    def from_args(
        cls, args: argparse.Namespace, *, device: str | None = None, default_device: str = ""
    ) -> DeviceCommand:
        """Flags over the config file; ``device`` overrides both (e.g. ``serve --mount``),
        ``default_device`` applies when neither names one (``serve`` runs the simulator)."""
        config = read_config()
        text = device or args.device or config.device or default_device
        if not text:
            text = _running_serve_or_hint()
        try:
            spec = parse_device(text)
        except DeviceOpenError as error:
            raise CommandError(str(error), error.hint) from None
        if not (device or args.device or default_device):
            spec = _serve_holding(spec)
        if spec.kind == SERVE_KIND and default_device:
            raise CommandError("scopelink serve cannot drive another serve's mount")
        site = parse_site(args.site) if args.site else config.site
        if args.timeout is not None and not args.timeout > 0:
            raise CommandError(f"--timeout must be positive, not {args.timeout}")
        sends_site = getattr(args, "command", None) == "site"
        return cls(spec, site, config, positive_rate(args.clock_rate), args.timeout, sends_site)


def _running_serve_or_hint() -> str:
    """``serve`` when a scopelink serve of this user runs here; else the one-line hint."""
    from scopelink.cli.serve_registry import running_serves  # noqa: PLC0415 - light

    if running_serves():
        return SERVE_KIND
    raise CommandError(
        "no device given, and no scopelink serve is running",
        f"start 'scopelink serve' (the commands then drive its mount), add --device DEVICE "
        f'({EXAMPLES}), or set device = "..." in {config_path()}',
    )


def _serve_holding(spec: DeviceSpec) -> DeviceSpec:
    """The config's device, or the running serve when that serve holds this very device (its
    port is then busy): never a simulator, which lives in each command's own process."""
    if spec.kind in ("sim", SERVE_KIND):
        return spec
    holder = _serve_of(spec)
    return spec if holder is None else DeviceSpec(SERVE_KIND, str(holder))


def _serve_of(spec: DeviceSpec) -> int | None:
    """The PID of this user's running serve that holds the device ``spec`` names, if any."""
    from scopelink.cli.serve_registry import running_serves  # noqa: PLC0415 - light

    for entry in running_serves():
        if entry.about.get("device") == str(spec):
            return entry.pid
    return None


def parse_site(text: str) -> Site:
    try:
        latitude, longitude = (float(part) for part in text.split(","))
        return Site(latitude, longitude)
    except ValueError as error:
        raise CommandError(f"bad --site {text!r}: {error}", "give LAT,LON like 40.4,-3.7") from None


def mount_error(error: Exception) -> CommandError:
    """The one-line report of a failure the Mount API or the catalogue raised."""
    if isinstance(error, UnknownObjectError):
        return CommandError(str(error), "'HIP n', M/NGC/IC numbers, star and planet names work")
    if isinstance(error, EphemerisRangeError):
        return CommandError(str(error))
    if isinstance(error, LinkError):
        return CommandError(f"the link failed: {error}", "check the cable and the device's power")
    hint = next((h for kind, h in _HINTS.items() if isinstance(error, kind)), "")
    return CommandError(str(error), hint)


def run_on_mount(
    args: argparse.Namespace,
    body: Callable[[Mount], Awaitable[int]],
    *,
    long_running: bool = False,
) -> int:
    """Open the device ``args`` name, run ``body`` on it, disconnect; the body's exit status.
    A ``long_running`` session (``track`` following a target) runs on
    :func:`long_session_loop`'s loop, a one-shot command on asyncio's default loop."""
    command = DeviceCommand.from_args(args)
    loop_factory = long_session_loop().factory if long_running else None
    if args.trace or getattr(args, "verbose", 0):
        trace_logger.setLevel(logging.DEBUG)
        if not logging.getLogger().handlers:
            logging.basicConfig(format="%(asctime)s %(name)s %(message)s")
    with asyncio.Runner(loop_factory=loop_factory) as runner:
        return runner.run(_run(command, body))


def long_session_loop() -> EventLoopChoice:
    """The event loop of a long-running session (``serve``, ``track`` following a target):
    uvloop where installed, unless ``SCOPELINK_EVENT_LOOP`` says otherwise (``docs/serve.md``,
    "Event loop"); a bad value is a one-line error."""
    try:
        return choose_event_loop()
    except EventLoopChoiceError as error:
        raise CommandError(
            str(error), f"unset it, or set it to {', '.join(EVENT_LOOP_CHOICES)}"
        ) from None


async def open_device(command: DeviceCommand) -> Mount:
    """The connected mount ``command`` names, or a :class:`CommandError` with a hint."""
    try:
        mount = await open_mount(
            command.device,
            command.site,
            command.config.limits,
            clock_rate=command.clock_rate,
            timeout_s=command.timeout_s,
        )
    except DeviceOpenError as error:
        busy = error.unopenable and PORT_BUSY in str(error)
        holder = _serve_of(command.device) if busy else None
        if holder is not None:  # the port is busy because our own serve has it
            hint = f"scopelink serve (PID {holder}) holds it: give --device serve to drive it"
            raise CommandError(str(error), hint) from None
        raise CommandError(str(error), error.hint) from None
    mount.stale_after_s = command.config.stale_after_s
    if command.config.park is not None:  # [park] in the settings file
        mount.park_position = command.config.park
    if mount.identity.protocol != "simulator":  # a new simulator starts afresh: nothing to keep
        mount.park_keeper.enable()  # the park record, for unpark after a power cycle
    mount.poll_policy = command.config.poll_policy
    warn_if_sun_unguarded(mount.limits)
    return mount


def warn_if_sun_unguarded(limits: Limits) -> None:
    """Say in red on stderr that nothing keeps the mount off the Sun, when that is so."""
    if limits.sun_avoidance_deg > 0.0:
        return
    Console(stderr=True, highlight=False).print(
        "[bold red]warning: Sun avoidance is OFF (limits.sun_avoidance_deg = 0): nothing stops "
        "this mount pointing at the Sun[/]"
    )


async def _run(command: DeviceCommand, body: Callable[[Mount], Awaitable[int]]) -> int:
    if command.device.kind == SERVE_KIND:
        return await _run_on_serve(command, body)
    mount = await open_device(command)
    # The syncs kept on the PC for this device (docs/pointing.md): 'scopelink sync' adds one,
    # and every other command reads and moves through them.
    mount.keep_pointing_in(DeviceMemory(device_key(mount.identity)))
    try:
        return await _one_line_errors(body(mount))
    finally:
        try:
            await mount.disconnect()
        except (MountError, LinkError) as error:
            _log.warning("while disconnecting: %s", error)


async def _run_on_serve(command: DeviceCommand, body: Callable[[Mount], Awaitable[int]]) -> int:
    """``body`` on the mount of a running serve, through its dashboard (cli/serve_mount.py):
    every command runs through the serve's own Mount and its guard."""
    from scopelink.cli.serve_mount import ServeMount  # noqa: PLC0415 - only for a serve
    from scopelink.cli.serve_registry import running_serves  # noqa: PLC0415

    serves = running_serves()
    wanted = command.device.target
    chosen = [entry for entry in serves if not wanted or str(entry.pid) == wanted]
    if not chosen:
        which = f"with PID {wanted} " if wanted else ""
        raise CommandError(
            f"no scopelink serve {which}is running for this user on this machine",
            "start one with 'scopelink serve', or give --device DEVICE",
        )
    if len(chosen) > 1:
        pids = ", ".join(str(entry.pid) for entry in chosen)
        raise CommandError(
            f"{len(chosen)} scopelink serves are running (PIDs {pids})",
            f"say which: --device serve:{chosen[0].pid}",
        )

    async def on_serve() -> int:
        mount = await ServeMount.open(chosen[0])
        if command.site_given:  # 'scopelink site' sends the configured site or --site
            mount.site = command.site
        try:
            return await body(cast(Mount, mount))
        finally:
            await mount.disconnect()

    return await _one_line_errors(on_serve())


async def _one_line_errors(running: Awaitable[int]) -> int:
    """A command's exit status; what the mount, the link or the catalogue raised, in one line."""
    try:
        return await running
    except (MountError, LinkError, UnknownObjectError, EphemerisRangeError) as error:
        raise mount_error(error) from None
    except TimeoutError:
        raise CommandError(
            "the mount did not report the end of the command in time",
            "'scopelink status' shows what it is doing; 'scopelink stop' stops it",
        ) from None
