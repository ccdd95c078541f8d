"""The devices behind the parsers: the SynScan, Sky Tracker / Sky Commander and LX200 emulated
devices, and every Alpaca setter of the telescope device."""

from __future__ import annotations

import asyncio
import random
import re
from collections.abc import Callable
from dataclasses import dataclass
from urllib.parse import parse_qsl

from bench.fuzz_targets.base import (
    SCRATCH_DIR,
    Target,
    event_loop,
    expect,
)
from bench.fuzz_targets.planetarium import LX200_COMMANDS, LX200_TOKENS
from bench.fuzz_targets.skytracker import TRACKER_COMMANDS, TRACKER_TOKENS
from bench.fuzz_targets.synscan import (
    SYNSCAN_COMMAND_ERRORS,
    SYNSCAN_COMMAND_SEEDS,
    SYNSCAN_COMMAND_TOKENS,
)
from scopelink.astro import Site
from scopelink.links import memory_pair
from scopelink.protocol import lx200, skytracker, synscan
from scopelink.servers.alpaca.errors import AlpacaError, BadRequest
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope import TelescopeDevice
from scopelink.servers.lx200.device import LX200Handset
from scopelink.servers.skytracker.commander import SkyCommander
from scopelink.servers.skytracker.emulator import commander_for
from scopelink.servers.skytracker.tracker import SkyTracker
from scopelink.servers.synscan.device import SynScanHandControl
from scopelink.sim import AZ_GTI, EQ6, SKY_TRACKER, SimClock, SimulatedMount


@dataclass
class _Devices:
    """The servers' device logic in front of simulated mounts, kept for the whole run (so a
    device target's input meets the state earlier inputs left, as a long session would)."""

    mount: SimulatedMount
    synscan: SynScanHandControl
    lx200: LX200Handset
    tracker: SkyTracker
    commander: SkyCommander


_DEVICES: list[_Devices] = []
_DEVICE_COMMANDS_PER_INPUT = 4
"""A device answers in real time (a cancelled goto waits up to ~0.2 s for the axes to stop): four
commands keep an input well inside the 1 s hang budget."""


def _devices() -> _Devices:
    if not _DEVICES:
        site = Site(latitude_deg=50.0, longitude_deg=10.0, elevation_m=300.0)
        mount = SimulatedMount(EQ6, site=site, clock=SimClock.accelerated(50.0))
        event_loop().run_until_complete(mount.connect())
        alt_az = SimulatedMount(SKY_TRACKER, site=site, clock=SimClock.accelerated(50.0))
        SCRATCH_DIR.mkdir(exist_ok=True)
        azimuth, altitude = alt_az.axes
        bus, _ = memory_pair()
        tracker = SkyTracker(
            altitude=altitude, azimuth=azimuth, clock=alt_az.clock, bus=bus, data_dir=SCRATCH_DIR
        )
        commander = commander_for(alt_az, SCRATCH_DIR)
        hand_control, handset = SynScanHandControl(mount), LX200Handset(mount)
        _DEVICES.append(_Devices(mount, hand_control, handset, tracker, commander))
    return _DEVICES[0]


def check_synscan_device(data: bytes, rng: random.Random) -> None:
    """The SynScan hand control behind the parser: every command gets a reply that fits it; a
    refusal is '#', never an exception (MountError is the device's to turn into '#')."""
    hand_control = _devices().synscan
    connection = synscan.SynScanServerConnection()
    connection.receive_data(data)
    answered = 0
    while (event := connection.next_event()) is not synscan.NEED_DATA:
        if isinstance(event, SYNSCAN_COMMAND_ERRORS):
            continue
        if answered == _DEVICE_COMMANDS_PER_INPUT:
            break
        answered += 1
        reply = event_loop().run_until_complete(asyncio.wait_for(hand_control.answer(event), 5))
        expect(synscan.reply_fits(event, reply), f"{reply!r} does not answer {event!r}")
        connection.send(reply)


def check_skytracker_device(data: bytes, rng: random.Random) -> None:
    """The Sky Tracker's firmware (``handle``) and the Sky Commander's (``respond``) behind their
    parsers: each reply is exactly as long as the client will read for that command."""
    devices = _devices()
    tracker = skytracker.TrackerServer()
    commander = skytracker.CommanderServer()
    tracker.receive_data(data)
    while (event := tracker.next_event()) is not skytracker.NEED_DATA:
        if event is skytracker.PAUSED:
            tracker.grant()  # the emulator relays to the Sky Commander; its replies checked below
            continue
        if isinstance(event, skytracker.RelayToCommander):
            commander.receive_data(event.data)
            while (relayed := commander.next_event()) is not skytracker.NEED_DATA:
                _expect_reply_length(relayed, devices.commander.respond(relayed))
            continue
        if isinstance(event, skytracker.ReleaseBus | skytracker.RequestBus):
            continue  # the bus is the emulator's (async) business, not the firmware's
        _expect_reply_length(event, devices.tracker.handle(event))


def _expect_reply_length(event: object, reply: bytes) -> None:
    expected = event.reply.size if isinstance(event, skytracker.Command) and event.reply else 0
    refused_calibration = isinstance(event, skytracker.SetCalibration) and not reply
    expect(len(reply) == expected or refused_calibration, f"{event!r} answered {reply!r}")


_LX200_REPLY = {
    lx200.ReplyKind.NONE: re.compile(rb""),
    lx200.ReplyKind.CHAR: re.compile(rb"[^#]"),
    lx200.ReplyKind.TERMINATED: re.compile(rb"[^#]*#"),
    lx200.ReplyKind.SLEW: re.compile(rb"0|[12][^#]*#"),
    lx200.ReplyKind.DATE_SET: re.compile(rb"0|1[^#]*#[^#]*#"),
}


def check_lx200_device(data: bytes, rng: random.Random) -> None:
    """The LX200 handset behind the parser: each reply has the shape its command's kind says
    (what the client reads by), and nothing raises."""
    session = _devices().lx200.session()
    connection = lx200.LX200ServerConnection()
    connection.receive_data(data + b"#")
    answered = 0
    while (event := connection.next_event()) is not lx200.NEED_DATA:
        if isinstance(event, lx200.UnknownCommand | lx200.StrayBytes):
            continue
        if answered == _DEVICE_COMMANDS_PER_INPUT:
            break
        answered += 1
        reply = event_loop().run_until_complete(asyncio.wait_for(session.answer(event), 5))
        shape = _LX200_REPLY[lx200.reply_kind(event)]
        expect(shape.fullmatch(reply) is not None, f"{event!r} answered {reply!r}")


# ------------------------------------------------------------------------- Alpaca setters


_SETTERS = {
    "utcdate": "UTCDate",
    "sitelatitude": "SiteLatitude",
    "sitelongitude": "SiteLongitude",
    "siteelevation": "SiteElevation",
    "trackingrate": "TrackingRate",
    "slewsettletime": "SlewSettleTime",
    "targetrightascension": "TargetRightAscension",
    "targetdeclination": "TargetDeclination",
    "guideraterightascension": "GuideRateRightAscension",
    "guideratedeclination": "GuideRateDeclination",
    "rightascensionrate": "RightAscensionRate",
    "declinationrate": "DeclinationRate",
    "tracking": "Tracking",
    "setpark": "ClientID",
}
"""Every ITelescopeV4 setter (member -> its parameter); SetPark takes the current position."""
_USABLE_READS = ("altitude", "rightascension", "siderealtime", "utcdate", "devicestate", "atpark")
_SETTER_DEVICES: list[tuple[TelescopeDevice, SimulatedMount]] = []


def _setter_devices() -> list[tuple[TelescopeDevice, SimulatedMount]]:
    """An equatorial and an alt-az simulated mount behind the Alpaca device, kept for the whole
    run: whatever one input set, the next meets (as one long session would)."""
    if not _SETTER_DEVICES:
        site = Site(latitude_deg=50.0, longitude_deg=10.0, elevation_m=300.0)
        for model in (EQ6, AZ_GTI):
            mount = SimulatedMount(model, site=site, clock=SimClock.stepped())
            device = TelescopeDevice(mount)
            event_loop().run_until_complete(device.connect())
            _SETTER_DEVICES.append((device, mount))
    return _SETTER_DEVICES


def _answer(handler: Callable[[Params], object], params: Params) -> int:
    """The ErrorNumber a handler's call would be answered with (0 for success)."""
    try:
        result = handler(params)
        if asyncio.iscoroutine(result):
            event_loop().run_until_complete(result)
    except AlpacaError as error:
        return int(error.number)
    except BadRequest:
        return 400  # HTTP 400: the request itself is malformed
    return 0


def check_alpaca_setters(data: bytes, rng: random.Random) -> None:
    """Each setter's PUT, with any value: a refusal is 0x400/0x401/0x402/0x408/0x40B with a
    reason, never 0x500 nor an exception; and whatever was accepted, every read still answers."""
    text = data.decode("utf-8", "replace")
    pairs = parse_qsl(text, keep_blank_values=True)
    for device, mount in _setter_devices():
        for name, value in pairs[:4]:
            # A name that is no setter's gives its value to a setter picked at random.
            setter = name.lower() if name.lower() in _SETTERS else rng.choice(list(_SETTERS))
            put = device.members[setter].put
            assert put is not None
            params = Params.from_pairs([(_SETTERS[setter], value)], exact=rng.random() < 0.5)
            number = _answer(put, params)
            expect(number != 0x500, f"{setter}={value!r} answered 0x500")
        mount.step(1.0)  # time moves on, as it does at night (a date at the end of time fails)
        for read in _USABLE_READS:
            getter = device.members[read].get
            assert getter is not None
            number = _answer(getter, Params.from_pairs([], exact=False))
            expect(number == 0, f"after {text!r}, {read} answered {number:#x}")


SERIAL_DEVICES: tuple[Target, ...] = (
    Target(
        "synscan-device",
        SYNSCAN_COMMAND_SEEDS,
        check_synscan_device,
        SYNSCAN_COMMAND_TOKENS,
        max_size=64,
        share=0.05,
    ),
    Target(
        "skytracker-device",
        (*(command.encode() for command in TRACKER_COMMANDS), b"QL99 05.588 -05.391\rOR\rq"),
        check_skytracker_device,
        TRACKER_TOKENS,
        max_size=64,
        share=0.25,
    ),
    Target(
        "lx200-device",
        LX200_COMMANDS,
        check_lx200_device,
        LX200_TOKENS,
        max_size=64,
        share=0.05,
    ),
)
ALPACA_SETTERS = Target(
    "alpaca-setters",
    (
        b"UTCDate=2026-11-24T21:30:00.1234567Z",
        b"UTCDate=2099-12-31T23:59:59%2B05:00",
        b"SiteLatitude=-33.9&SiteLongitude=18.4&SiteElevation=10",
        b"TrackingRate=2&Tracking=true",
        b"SlewSettleTime=5",
        b"TargetRightAscension=23.99&TargetDeclination=-90",
        b"GuideRateRightAscension=0.002&RightAscensionRate=0",
        b"SetPark=1",
    ),
    check_alpaca_setters,
    b"=&%+.:-TZeE0123456789",
    share=0.25,
)
