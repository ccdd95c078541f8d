"""What `bench.fuzz` and tests/test_fuzz_parsers.py fuzz: one `Target` per parser.

A target is a few valid inputs (its seeds: frames, requests, files) and a `check` that feeds one
input to the parser, in chunks the given `random.Random` chooses, and raises `FuzzFailureError`
when an invariant breaks. Any other exception escaping `check` is a crash: the only exceptions a
parser may raise are the documented error types, which `check` catches itself.

The invariants, per parser (docs/reliability-fuzzing.md has the table):

- only the documented event types come out, and every event consumes at least one byte (no
  parser can loop on its own input);
- every byte is accounted for (stream offset + bytes held back = bytes fed);
- round trips: a decoded command re-encodes to a frame that decodes to the same command;
- recovery: after any garbage, the spec's recovery step (an inter-byte pause, a ``#``, ``reset()``
  and a unique echo, ``abandon_reply()``) leaves the parser in step, and valid frames sent next
  come out exactly, in any chunking.
"""

from __future__ import annotations

import asyncio
import logging
import os
import random
import re
import tempfile
import typing
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import parse_qsl

from aiohttp import web

from scopelink.astro import Site
from scopelink.cli.config import ConfigError, load_config
from scopelink.cli.errors import CommandError
from scopelink.cli.targets import Coordinates, parse_target
from scopelink.decode import Direction, Protocol, TraceInputError, annotate, parse_trace
from scopelink.links import memory_pair
from scopelink.mount import MountAxis, TrackingMode
from scopelink.protocol import lx200, skytracker, stellarium, synscan
from scopelink.protocol.skytracker import commander_messages
from scopelink.protocol.skytracker import messages as tracker_messages
from scopelink.servers.access import AccessControl
from scopelink.servers.alpaca.errors import AlpacaError, BadRequest
from scopelink.servers.alpaca.http import AlpacaHttpFront, HttpReply, HttpRequest
from scopelink.servers.alpaca.params import UINT32_MAX, Params, parse_transaction_id
from scopelink.servers.alpaca.telescope import TelescopeDevice
from scopelink.servers.hosts import HostAllowList
from scopelink.servers.http_guard import (
    GuardedAppRunner,
    GuardedRequestHandler,
    GuardedServer,
    HttpGuard,
)
from scopelink.servers.lx200.device import LX200Handset
from scopelink.servers.skytracker.commander import SkyCommander
from scopelink.servers.skytracker.emulator import commander_for
from scopelink.servers.skytracker.tracker import SkyTracker
from scopelink.servers.synscan.device import SynScanHandControl
from scopelink.sim import AZ_GTI, EQ6, SKY_TRACKER, SimClock, SimulatedMount
from scopelink.web.params import BadRequestError, read_body

__all__ = ["TARGETS", "FuzzFailureError", "Target", "chunks"]


class FuzzFailureError(AssertionError):
    """A parser broke one of its invariants on this input."""


def expect(condition: bool, message: str) -> None:
    if not condition:
        raise FuzzFailureError(message)


@dataclass(frozen=True, slots=True)
class Target:
    name: str
    seeds: tuple[bytes, ...]
    """Valid inputs; the generator mutates, splices and concatenates them."""
    check: Callable[[bytes, random.Random], None]
    tokens: bytes = b""
    """Bytes that mean something to this parser (delimiters, command letters), inserted more
    often."""
    max_size: int = 256
    share: float = 1.0
    """This target's inputs relative to a parser's (devices answer in real time: fewer inputs)."""


def chunks(data: bytes, rng: random.Random) -> Iterator[bytes]:
    """``data`` cut where ``rng`` says: whole, a few random cuts, or byte by byte."""
    style = rng.random()
    if style < 0.3 or len(data) < 2:
        yield data
        return
    if style < 0.4:
        yield from (data[index : index + 1] for index in range(len(data)))
        return
    cuts = sorted(rng.sample(range(1, len(data)), min(len(data) - 1, rng.randint(1, 4))))
    start = 0
    for cut in [*cuts, len(data)]:
        yield data[start:cut]
        start = cut


class _Parser(typing.Protocol):
    def receive_data(self, data: bytes) -> None: ...

    def next_event(self) -> object: ...


def parsed_in_chunks(
    parser: _Parser, stream: bytes, rng: random.Random, need_data: object
) -> list[typing.Any]:
    """Every event ``parser`` yields for ``stream`` fed in :func:`chunks`."""
    events = []
    for chunk in chunks(stream, rng):
        parser.receive_data(chunk)
        while (event := parser.next_event()) is not need_data:
            events.append(event)
    return events


def _progress_guard(count: int, fed: int) -> None:
    # Each event consumes at least one byte; a few more (a pause, a release) are allowed for.
    expect(count <= fed + 4, f"{count} events from {fed} bytes: the parser does not advance")


# ----------------------------------------------------------------------------------- SynScan


_SYNSCAN_EXCHANGES: tuple[tuple[synscan.AnyCommand, synscan.AnyReply], ...] = (
    (synscan.GetRaDec(True), synscan.Position(synscan.Frame.EQUATORIAL, 0x34AB0500, 0x12CE0500)),
    (synscan.GetRaDec(False), synscan.Position(synscan.Frame.EQUATORIAL, 0x34AB, 0x12CE, False)),
    (synscan.GetAzAlt(True), synscan.Position(synscan.Frame.HORIZONTAL, 0x1000, 0xFFFFFF00)),
    (synscan.GotoRaDec(0x34AB0500, 0x12CE0500), synscan.Ack()),
    (synscan.SyncRaDec(0x1234, 0x4321, False), synscan.Ack()),
    (synscan.GotoAzAlt(0x8000, 0x0400, False), synscan.Ack()),
    (synscan.GetTrackingMode(), synscan.TrackingModeReply(2)),
    (synscan.SetTrackingMode(1), synscan.Ack()),
    (synscan.VariableRateSlew(synscan.Axis.AZM_RA, True, 1200), synscan.Ack()),
    (synscan.FixedRateSlew(synscan.Axis.ALT_DEC, False, 9), synscan.Ack()),
    (synscan.GetDeviceVersion(synscan.Axis.AZM_RA), synscan.DeviceVersion(3, 39)),
    (synscan.SlowGoto(synscan.Axis.ALT_DEC, 0x123456), synscan.Ack()),
    (synscan.GetLocation(), synscan.Location(51, 28, 40, False, 0, 0, 5, True)),
    (synscan.SetLocation(synscan.Location(33, 51, 35, True, 151, 12, 40, False)), synscan.Ack()),
    (synscan.GetTime(), synscan.DateTime(22, 5, 0, 11, 23, 2026, -5, False)),
    (synscan.SetTime(synscan.DateTime(1, 2, 3, 4, 5, 2030, 10, True)), synscan.Ack()),
    (synscan.GetVersion(), synscan.Version(4, 39, 7)),
    (synscan.GetModel(), synscan.Model(0)),
    (synscan.Echo(0x23), synscan.EchoReply(0x23)),
    (synscan.IsAligned(), synscan.Aligned(True)),
    (synscan.IsGotoInProgress(), synscan.GotoInProgress(False)),
    (synscan.CancelGoto(), synscan.Ack()),
    (synscan.GetPointingState(), synscan.PointingState(synscan.PointingSide.WEST)),
)
_SYNSCAN_COMMANDS = tuple(command for command, _ in _SYNSCAN_EXCHANGES)
_SYNSCAN_ERRORS = (synscan.UnknownCommand, synscan.MalformedCommand)
_HASH = 0x23


def _is_synscan_command(event: object) -> bool:
    return isinstance(event, synscan.Command)


def check_synscan_server(data: bytes, rng: random.Random) -> None:
    """The hand control's command parser; recovery is the inter-byte pause (discard_partial)."""
    connection = synscan.SynScanServerConnection()
    count = 0
    for chunk in chunks(data, rng):
        connection.receive_data(chunk)
        while (event := connection.next_event()) is not synscan.NEED_DATA:
            count += 1
            _progress_guard(count, len(data))
            if isinstance(event, _SYNSCAN_ERRORS):
                continue
            expect(_is_synscan_command(event), f"unexpected event {event!r}")
            frame = synscan.encode_command(event)
            again = synscan.decode_command_frame(frame)
            expect(again == event, f"{event!r} re-encodes to {frame!r}, which reads {again!r}")
    parser = connection.parser
    expect(parser.offset + len(parser.pending) == len(data), "bytes lost or invented")
    connection.discard_partial()
    valid = [rng.choice(_SYNSCAN_COMMANDS) for _ in range(rng.randint(1, 3))]
    stream = b"".join(synscan.encode_command(command) for command in valid)
    events = parsed_in_chunks(connection, stream, rng, synscan.NEED_DATA)
    expect(events == valid, f"valid commands after the pause came out as {events!r}")


def check_synscan_client(data: bytes, rng: random.Random) -> None:
    """The driver's reply parser: any reply bytes; then reset(), late bytes and a unique echo."""
    command, _ = rng.choice(_SYNSCAN_EXCHANGES)
    client = synscan.SynScanClientConnection()
    client.send(command)
    split = rng.randint(0, len(data))
    early, late = data[:split], data[split:]
    accounted = 0
    answers = 0
    for chunk in chunks(early, rng):
        client.receive_data(chunk)
        while (event := client.next_event()) is not synscan.NEED_DATA:
            match event:
                case synscan.UnexpectedData(stray):
                    accounted += len(stray)
                case synscan.MalformedReply(data=read):
                    answers += 1
                    accounted += len(read)
                case synscan.Reply():
                    answers += 1
                    encoded = synscan.encode_reply(event)
                    expect(synscan.reply_fits(command, event), f"{event!r} answers {command!r}")
                    expect(synscan.parse_reply(command, encoded) == event, f"{event!r} round trip")
                    accounted += len(encoded)
                case _:
                    raise FuzzFailureError(f"unexpected event {event!r}")
            expect(answers <= 1, "two answers to one command")
    accounted += len(client.reset())
    expect(accounted == len(early), f"{accounted} bytes accounted for, {len(early)} fed")
    free = [value for value in range(0x80, 0x100) if value not in late]
    if not free:
        return
    echo = rng.choice(free)
    client.send(synscan.Echo(echo))
    events = parsed_in_chunks(client, late + bytes((echo, _HASH)), rng, synscan.NEED_DATA)
    stray = b"".join(e.data for e in events if isinstance(e, synscan.UnexpectedData))
    expect(events[-1:] == [synscan.EchoReply(echo)], f"resync echo not found: {events!r}")
    expect(stray == late, "late bytes not all drained as UnexpectedData")
    command, reply = rng.choice(_SYNSCAN_EXCHANGES)
    client.send(command)
    events = parsed_in_chunks(client, synscan.encode_reply(reply), rng, synscan.NEED_DATA)
    expect(events == [reply], f"valid reply after resync came out as {events!r}")


# ------------------------------------------------------------------ Sky Tracker / Sky Commander


_TRACKER_COMMANDS: tuple[skytracker.TrackerCommand, ...] = (
    *(
        command
        for command in tracker_messages.SINGLE_BYTE_COMMANDS.values()
        if not isinstance(command, skytracker.RequestBus | skytracker.ReleaseBus)
    ),
    skytracker.SetCalibration(1.5, 2.25),
    skytracker.SetGuideSpeed(15, 30),
)
_TRACKER_EXCHANGES: tuple[tuple[skytracker.TrackerCommand, skytracker.Reply], ...] = (
    (skytracker.ReadStatus(), skytracker.StatusReply(skytracker.TrackerStatus.from_byte(0x05))),
    (skytracker.ReadCalibration(), skytracker.CalibrationReply(1.5, 2.25)),
    (skytracker.ReadVersion(), skytracker.VersionReply.padded("1.2")),
    (skytracker.ReadGuideSpeed(), skytracker.GuideSpeedReply(15, 30)),
    (skytracker.SetCalibration(3.0, 0.75), skytracker.Acknowledge()),
    (skytracker.RequestBus(), skytracker.BusAnswer(granted=True)),
    (skytracker.RequestBus(), skytracker.BusAnswer(granted=False)),
)
_COMMANDER_COMMANDS: tuple[skytracker.CommanderCommand, ...] = (
    *commander_messages.SINGLE_BYTE_COMMANDS.values(),
    skytracker.LoadObject(99, 5.588, -5.391),
    skytracker.LoadObject(0, 23.999, 89.999),
)
_COMMANDER_EXCHANGES: tuple[tuple[skytracker.CommanderCommand, skytracker.Reply], ...] = (
    (skytracker.ReadPosition(), skytracker.PositionReply(5.5, -20.25)),
    (skytracker.ReadOffsets(), skytracker.OffsetsReply(1.0, -2.5)),
    (skytracker.ReadRates(), skytracker.RatesReply(0.25, 0.125)),
    (skytracker.LoadObject(99, 12.0, 45.0), skytracker.Acknowledge()),
)
_TRACKER_SERVER_EVENTS = (
    skytracker.TrackerCommand,
    skytracker.RelayToCommander,
    skytracker.UnknownCommand,
)
_COMMANDER_SERVER_EVENTS = (skytracker.CommanderCommand, skytracker.ErrorEvent)
_CLIENT_EVENTS = (skytracker.Reply, skytracker.StrayByte, skytracker.BadReply)


def _drain_commander(server: skytracker.CommanderServer, fed: int) -> list[object]:
    events: list[object] = []
    while (event := server.next_event()) is not skytracker.NEED_DATA:
        events.append(event)
        _progress_guard(len(events), fed)
        expect(isinstance(event, _COMMANDER_SERVER_EVENTS), f"unexpected event {event!r}")
    return events


def check_skytracker_server(data: bytes, rng: random.Random) -> None:
    """The Sky Tracker's parser, bus grants included; relayed bytes go on to a Sky Commander."""
    tracker = skytracker.TrackerServer()
    commander = skytracker.CommanderServer()
    relayed = 0
    count = 0
    for chunk in chunks(data, rng):
        tracker.receive_data(chunk)
        while (event := tracker.next_event()) is not skytracker.NEED_DATA:
            if event is skytracker.PAUSED:  # a wait for our answer to Q, not an event
                tracker.grant() if rng.random() < 0.7 else tracker.refuse()
                continue
            count += 1
            _progress_guard(count, len(data))
            expect(isinstance(event, _TRACKER_SERVER_EVENTS), f"unexpected event {event!r}")
            if isinstance(event, skytracker.RelayToCommander):
                relayed += len(event.data)
                commander.receive_data(event.data)
                _drain_commander(commander, relayed)
    expect(tracker.offset + len(tracker.buffered) == len(data), "bytes lost or invented")
    expect(commander.offset + len(commander.buffered) == relayed, "relayed bytes lost")
    if tracker.bus is skytracker.BusState.HELD:
        tracker.receive_data(b"q")
        while (event := tracker.next_event()) is not skytracker.NEED_DATA:
            expect(isinstance(event, skytracker.RelayToCommander | skytracker.ReleaseBus), "q")
    expect(tracker.bus is skytracker.BusState.RELEASED, f"bus {tracker.bus} after release")
    tracker.discard_partial()
    valid = [rng.choice(_TRACKER_COMMANDS) for _ in range(rng.randint(1, 3))]
    stream = b"".join(command.encode() for command in valid)
    events = parsed_in_chunks(tracker, stream, rng, skytracker.NEED_DATA)
    expect(events == valid, f"valid commands after the pause came out as {events!r}")


def check_commander_server(data: bytes, rng: random.Random) -> None:
    """The Sky Commander's parser (single bytes and ``L`` lines up to CR)."""
    commander = skytracker.CommanderServer()
    for chunk in chunks(data, rng):
        commander.receive_data(chunk)
        for event in _drain_commander(commander, len(data)):
            if isinstance(event, skytracker.LoadObject):
                # Extra decimals are read, and rounded to the wire's 3 when encoded again.
                frame = event.encode()
                again = skytracker.LoadObject.decode(frame)
                expect(again.encode() == frame, f"{event!r} re-encodes unstably: {again!r}")
    expect(commander.offset + len(commander.buffered) == len(data), "bytes lost or invented")
    commander.discard_partial()
    valid = [rng.choice(_COMMANDER_COMMANDS) for _ in range(rng.randint(1, 3))]
    stream = b"".join(command.encode() for command in valid)
    events = []
    for chunk in chunks(stream, rng):
        commander.receive_data(chunk)
        events += _drain_commander(commander, len(stream))
    expect(events == valid, f"valid commands after the pause came out as {events!r}")


def _check_reply_reader(
    client: skytracker.TrackerClient | skytracker.CommanderClient,
    command: skytracker.Command,
    data: bytes,
    rng: random.Random,
) -> None:
    answers = 0
    for chunk in chunks(data, rng):
        client.receive_data(chunk)
        while (event := client.next_event()) is not skytracker.NEED_DATA:
            expect(isinstance(event, _CLIENT_EVENTS), f"unexpected event {event!r}")
            if isinstance(event, skytracker.Reply | skytracker.BadReply):
                answers += 1
                expect(answers <= 1, "two answers to one command")
            if isinstance(event, skytracker.Reply):
                expect(command.reply is not None and isinstance(event, command.reply), "type")
                # Decoding is lenient (INDI's sscanf); a re-encoded reply must then be stable.
                frame = event.encode()
                again = type(event).decode(frame)
                expect(again.encode() == frame, f"{event!r} re-encodes unstably: {again!r}")
    expect(client.offset + len(client.buffered) == len(data), "bytes lost or invented")
    client.abandon_reply()
    while (event := client.next_event()) is not skytracker.NEED_DATA:
        expect(isinstance(event, skytracker.StrayByte), f"after abandon_reply: {event!r}")
    expect(not client.buffered, "bytes left after draining strays")


def _expect_reply(
    client: skytracker.TrackerClient | skytracker.CommanderClient,
    reply: skytracker.Reply,
    rng: random.Random,
) -> None:
    events = parsed_in_chunks(client, reply.encode(), rng, skytracker.NEED_DATA)
    expect(events == [reply], f"valid reply {reply!r} came out as {events!r}")


def check_skytracker_client(data: bytes, rng: random.Random) -> None:
    """The driver's Sky Tracker reply reader (and bus answers); then a valid exchange."""
    client = skytracker.TrackerClient()
    command, _ = rng.choice(_TRACKER_EXCHANGES)
    client.send(command)
    _check_reply_reader(client, command, data, rng)
    if client.bus is skytracker.BusState.HELD:
        client.send(skytracker.ReleaseBus())
    command, reply = rng.choice(_TRACKER_EXCHANGES)
    client.send(command)
    _expect_reply(client, reply, rng)


def check_commander_client(data: bytes, rng: random.Random) -> None:
    """The Sky Commander reply reader (position, offsets, rates, acknowledge)."""
    client = skytracker.CommanderClient()
    command, _ = rng.choice(_COMMANDER_EXCHANGES)
    client.send(command)
    _check_reply_reader(client, command, data, rng)
    command, reply = rng.choice(_COMMANDER_EXCHANGES)
    client.send(command)
    _expect_reply(client, reply, rng)


# ----------------------------------------------------------------------------------------- LX200


_LX200_COMMANDS = (
    b":GR#",
    b":GD#",
    b":GA#",
    b":GZ#",
    b":Sr12:34:56#",
    b":Sd-05*23:15#",
    b":Sr05:35.2#",
    b":MS#",
    b":CM#",
    b":Q#",
    b":Mn#",
    b":Qe#",
    b":RS#",
    b":Mgw0500#",
    b":St+51*28#",
    b":Sg359*58#",
    b":SG-01.0#",
    b":SL22:05:00#",
    b":SC11/23/26#",
    b":U#",
    b"\x06",
)
_LX200_EVENTS = (
    *typing.get_args(lx200.AnyCommand),
    lx200.UnknownCommand,
    lx200.MalformedCommand,
    lx200.StrayBytes,
)


def _lx200_events(
    connection: lx200.LX200ServerConnection, data: bytes, rng: random.Random
) -> list[object]:
    events: list[object] = []
    for chunk in chunks(data, rng):
        connection.receive_data(chunk)
        while (event := connection.next_event()) is not lx200.NEED_DATA:
            events.append(event)
            _progress_guard(len(events), len(data))
            expect(isinstance(event, _LX200_EVENTS), f"unexpected event {event!r}")
    return events


def check_lx200_server(data: bytes, rng: random.Random) -> None:
    """The handset side's command framing and parsing; any garbage is ended by a ``#``."""
    connection = lx200.LX200ServerConnection()
    _lx200_events(connection, data, rng)
    _lx200_events(connection, b"#", rng)
    expect(not connection.pending, "a '#' did not end the garbage")
    valid = [rng.choice(_LX200_COMMANDS) for _ in range(rng.randint(1, 3))]
    expected = [
        lx200.Ack() if frame == b"\x06" else lx200.parse_command(frame[1:-1].decode())
        for frame in valid
    ]
    events = _lx200_events(connection, b"".join(valid), rng)
    expect(events == expected, f"valid commands after '#' came out as {events!r}")


def check_skyfi(data: bytes, rng: random.Random) -> None:
    """SkySafari's SkyFi discovery datagrams (one datagram per input)."""
    query = lx200.parse_skyfi_query(data)
    if query is not None:
        query.matches(rng.choice((None, "scopelink", "SkyFi")))
        reply = lx200.skyfi_reply(query, "127.0.0.1")
        expect(lx200.parse_skyfi_query(reply) is None, "our own reply reads as a query")


# ------------------------------------------------------------------------------------ Stellarium


def _stellarium_frame(message_type: int, payload: bytes) -> bytes:
    return (4 + len(payload)).to_bytes(2, "little") + message_type.to_bytes(2, "little") + payload


_GOTOS = (
    stellarium.GotoMessage.from_degrees(5.5875, -5.391, 1_700_000_000_000_000),
    stellarium.GotoMessage.from_degrees(0.0, 90.0),
    stellarium.GotoMessage.from_degrees(23.99, -89.5, 42),
)
_POSITIONS = (
    stellarium.CurrentPosition.from_degrees(5.5875, -5.391, 1_700_000_000_000_000),
    stellarium.CurrentPosition.from_degrees(12.0, 45.0, 0, -1),
)
_STELLARIUM_JUNK = (_stellarium_frame(7, b"unknown"), _stellarium_frame(0, b""))
_STELLARIUM_EVENTS = (
    stellarium.GotoMessage,
    stellarium.CurrentPosition,
    stellarium.SkippedMessage,
    stellarium.BadLength,
)


def _check_stellarium(
    connection: stellarium.StellariumServerConnection | stellarium.StellariumClientConnection,
    valid: Sequence[stellarium.GotoMessage | stellarium.CurrentPosition],
    data: bytes,
    rng: random.Random,
) -> None:
    def events_of(stream: bytes) -> list[object]:
        events: list[object] = []
        for chunk in chunks(stream, rng):
            connection.receive_data(chunk)
            while (event := connection.next_event()) is not stellarium.NEED_DATA:
                events.append(event)
                _progress_guard(len(events), len(stream))
                expect(isinstance(event, _STELLARIUM_EVENTS), f"unexpected event {event!r}")
        return events

    events = events_of(data)
    for event in events:
        if isinstance(event, stellarium.GotoMessage | stellarium.CurrentPosition):
            again = type(event).decode(event.encode())
            expect(again == event, f"{event!r} round trip gives {again!r}")
    framing = _stellarium_framing(data)
    expect(connection.broken == (framing == "broken"), f"broken={connection.broken}, {framing}")
    tail = [rng.choice(valid) for _ in range(rng.randint(1, 3))]
    after = events_of(b"".join(message.encode() for message in tail))
    if framing == "broken":
        expect(after == [], f"a broken stream still yields {after!r}")
    elif framing == "whole frames":
        expect(after == tail, f"valid messages after whole frames came out as {after!r}")


def _stellarium_framing(data: bytes) -> str:
    """How the LENGTH fields cut ``data``, worked out independently of the codec."""
    position = 0
    while position + 4 <= len(data):
        length = int.from_bytes(data[position : position + 2], "little")
        if not 4 <= length <= stellarium.MAX_MESSAGE_LENGTH:
            return "broken"
        position += length
    return "whole frames" if position == len(data) else "partial frame"


def check_stellarium_server(data: bytes, rng: random.Random) -> None:
    """Gotos in (framed by LENGTH); a bad LENGTH breaks the stream for good, by design."""
    _check_stellarium(stellarium.StellariumServerConnection(), _GOTOS, data, rng)


def check_stellarium_client(data: bytes, rng: random.Random) -> None:
    """Current positions in (the planetarium's side)."""
    _check_stellarium(stellarium.StellariumClientConnection(), _POSITIONS, data, rng)


# ---------------------------------------------------------------------------------------- Alpaca


_ALPACA_NAMES = (
    "ClientID",
    "ClientTransactionID",
    "Connected",
    "Tracking",
    "RightAscension",
    "Declination",
    "Azimuth",
    "Altitude",
    "Axis",
    "Rate",
    "Direction",
    "Duration",
    "TrackingRate",
    "SideOfPier",
)


def _read_alpaca_params(params: Params, rng: random.Random) -> None:
    """Every typed read the telescope's members make, each one allowed only its documented
    errors (BadRequest: HTTP 400; AlpacaError: InvalidValue)."""
    names = list(_ALPACA_NAMES) + list(params.values)
    for name in rng.sample(names, min(len(names), 6)):
        for read in ("id", "text", "boolean", "number", "integer"):
            try:
                match read:
                    case "id":
                        value = parse_transaction_id(name, params.optional(name))
                        expect(0 <= value <= UINT32_MAX, f"transaction id {value}")
                    case "text":
                        params.text(name)
                    case "boolean":
                        expect(isinstance(params.boolean(name), bool), "boolean")
                    case "number":
                        number = params.number(name, -90.0, 90.0)
                        expect(-90.0 <= number <= 90.0, f"number {number} out of range")
                    case "integer":
                        integer = params.integer(name, 0, 3)
                        expect(0 <= integer <= 3, f"integer {integer} out of range")
            except (BadRequest, AlpacaError):
                pass


def check_alpaca_params(data: bytes, rng: random.Random) -> None:
    """Query strings and PUT form bodies -> Params -> typed values."""
    text = data.decode("utf-8", "replace")
    exact = rng.random() < 0.5
    params = Params.from_pairs(parse_qsl(text, keep_blank_values=True), exact=exact)
    _read_alpaca_params(params, rng)


class _Transport(asyncio.Transport):
    """Collects what the connection writes; the target is the HTTP stack, not a socket."""

    def __init__(self) -> None:
        super().__init__()
        self.written = bytearray()
        self.closed = False
        self.eof = False

    def write(self, data: bytes | bytearray | memoryview) -> None:
        expect(not self.closed and not self.eof, "wrote after close")
        self.written += data

    def close(self) -> None:
        self.closed = True

    def is_closing(self) -> bool:
        return self.closed

    def can_write_eof(self) -> bool:
        return True

    def write_eof(self) -> None:
        self.eof = True

    def get_extra_info(self, name: str, default: object = None) -> object:
        return ("127.0.0.1", 50000) if name == "peername" else default

    def pause_reading(self) -> None:
        pass

    def resume_reading(self) -> None:
        pass


async def _echo_params(request: HttpRequest) -> HttpReply:
    """A handler that reads what the Alpaca server reads: query or form parameters."""
    if request.method == "PUT":
        pairs = parse_qsl(request.body.decode("utf-8", "replace"), keep_blank_values=True)
        params = Params.from_pairs(pairs, exact=True)
    else:
        params = Params.from_pairs(request.query, exact=False)
    _read_alpaca_params(params, random.Random(len(request.path)))
    return HttpReply(200, b'{"ErrorNumber":0}', "application/json")


_HTTP_MAX_BODY = 1024
_HTTP_REQUESTS = (
    b"GET /api/v1/telescope/0/rightascension?ClientID=1&ClientTransactionID=7 HTTP/1.1\r\n"
    b"Host: 127.0.0.1\r\n\r\n",
    b"PUT /api/v1/telescope/0/slewtocoordinatesasync HTTP/1.1\r\nHost: x\r\n"
    b"Content-Type: application/x-www-form-urlencoded\r\nContent-Length: 40\r\n\r\n"
    b"RightAscension=12.5&Declination=-30&Cl=1",
    b"PUT /api/v1/telescope/0/tracking HTTP/1.1\r\nHost: x\r\nExpect: 100-continue\r\n"
    b"Transfer-Encoding: chunked\r\n\r\n5\r\nTrack\r\n9\r\ning=False\r\n0\r\n\r\n",
    b"GET /management/apiversions HTTP/1.1\r\nHost: [::1]:11111\r\nConnection: keep-alive\r\n\r\n",
    b"GET /setup HTTP/1.0\r\n\r\n",  # not kept alive: only ever last in a valid stream
)


def check_alpaca_http(data: bytes, rng: random.Random) -> None:
    """Raw bytes into one guarded aiohttp connection: replies well formed, no crash logged;
    then valid pipelined requests on a fresh connection get one 200 each (after any 100)."""
    crashes: list[dict[str, object]] = []
    _event_loop().set_exception_handler(lambda _, context: crashes.append(context))
    _HTTP_ERRORS.clear()
    statuses = _statuses(_serve(data, rng))
    expect(not crashes, f"the event loop saw {crashes!r}")
    expect(not _HTTP_ERRORS, f"logged as errors: {_HTTP_ERRORS[:3]}")
    expect(500 not in statuses, "a request reached 'internal server error'")
    valid = [rng.choice(_HTTP_REQUESTS[:-1]) for _ in range(rng.randint(1, 3))]
    stream = b"".join(valid)
    expected = [100] * stream.count(b"100-continue") + [200] * len(valid)
    statuses = _statuses(_serve(stream, rng))
    expect(sorted(statuses) == expected, f"valid requests answered {statuses}")
    expect(statuses[-1] == 200 and not crashes, f"valid requests answered {statuses}, {crashes}")


def _alpaca_server() -> GuardedServer:
    front = AlpacaHttpFront(
        _echo_params, AccessControl(), HostAllowList("127.0.0.1", ("x",)), _HTTP_MAX_BODY
    )
    return GuardedServer(front, guard=HttpGuard(AccessControl()), access_log=None)


def _serve(
    stream: bytes, rng: random.Random, make_server: Callable[[], GuardedServer] = _alpaca_server
) -> bytes:
    return _event_loop().run_until_complete(_serve_on_loop(stream, rng, make_server))


async def _serve_on_loop(
    stream: bytes, rng: random.Random, make_server: Callable[[], GuardedServer]
) -> bytes:
    """The real guarded aiohttp connection handler (Alpaca's front, or the dashboard's app), on
    a transport that records what it writes. Afterwards nothing of the connection is left in the
    guard: memory stays bounded however many inputs run."""
    transport = _Transport()
    server = make_server()
    connection = server()
    connection.connection_made(transport)
    try:
        for chunk in chunks(stream, rng):
            if transport.closed:
                break
            connection.data_received(chunk)
            await _settle(connection, transport)
        await _settle(connection, transport)
    finally:
        connection.connection_lost(None)
        await asyncio.sleep(0)
    expect(not server.guard.connections, "a closed connection stayed registered")
    return bytes(transport.written)


_DASHBOARD_REQUESTS = (
    b"GET /api/state HTTP/1.1\r\nHost: 127.0.0.1:8080\r\n\r\n",
    b"GET /api/search?q=M31 HTTP/1.1\r\nHost: localhost\r\nAccept: */*\r\n\r\n",
    b"POST /api/tracking HTTP/1.1\r\nHost: 127.0.0.1\r\nOrigin: http://127.0.0.1\r\n"
    b'Content-Type: application/json\r\nContent-Length: 20\r\n\r\n{"mode": "sidereal"}',
    b"POST /api/abort HTTP/1.1\r\nHost: [::1]:8080\r\nContent-Type: application/json\r\n"
    b"Transfer-Encoding: chunked\r\n\r\n2\r\n{}\r\n0\r\n\r\n",
    b"GET /api/access HTTP/1.1\r\nHost: 127.0.0.1\r\nCookie: a=b\r\n\r\n",
)


def check_dashboard_http(data: bytes, rng: random.Random) -> None:
    """Raw bytes into the dashboard's guarded aiohttp stack (its real application: Host and
    Origin checks, access, pairing, API): replies well formed, no 500, no crash logged; then
    valid pipelined requests get one 2xx each."""
    crashes: list[dict[str, object]] = []
    _event_loop().set_exception_handler(lambda _, context: crashes.append(context))
    _set_up_dashboard()
    _HTTP_ERRORS.clear()
    statuses = _statuses(_serve(data, rng, _dashboard_server))
    expect(not crashes, f"the event loop saw {crashes!r}")
    expect(not _HTTP_ERRORS, f"logged as errors: {_HTTP_ERRORS[:3]}")
    expect(500 not in statuses, "a request reached 'internal server error'")
    valid = [rng.choice(_DASHBOARD_REQUESTS) for _ in range(rng.randint(1, 3))]
    statuses = _statuses(_serve(b"".join(valid), rng, _dashboard_server))
    expect(len(statuses) == len(valid), f"valid requests answered {statuses}")
    expect(all(s in (200, 409) for s in statuses), f"valid requests answered {statuses}")


_DASHBOARD: list[GuardedServer] = []


def _dashboard_server() -> GuardedServer:
    """One dashboard application for every input (set up by :func:`_set_up_dashboard`)."""
    return _DASHBOARD[0]


def _set_up_dashboard() -> None:
    if _DASHBOARD:
        return
    import aiohttp.web_fileresponse

    from scopelink.sim import EQ6, SimulatedMount
    from scopelink.web import Dashboard

    # Static files go out by sendfile(2) on a real socket; the recording transport takes writes.
    aiohttp.web_fileresponse.NOSENDFILE = True  # type: ignore[misc]

    dashboard = Dashboard(SimulatedMount(EQ6, site=Site(50.0, 10.0)), port=0, trace=False)
    runner = GuardedAppRunner(dashboard.build_app(), dashboard.guard, access_log=None)
    _event_loop().run_until_complete(runner.setup())
    assert isinstance(runner.server, GuardedServer)
    _DASHBOARD.append(runner.server)


class _ErrorRecords(logging.Handler):
    """Collects what the HTTP stack logs as an error (an unhandled exception in a handler)."""

    def emit(self, record: logging.LogRecord) -> None:
        _HTTP_ERRORS.append(record.getMessage())


_HTTP_ERRORS: list[str] = []
for _name in ("aiohttp.server", "aiohttp.web", "scopelink.servers", "scopelink.web"):
    logging.getLogger(_name).addHandler(_ErrorRecords(logging.ERROR))

_STATUS_LINE = re.compile(rb"HTTP/\d\.\d \d{3} ")


def _statuses(written: bytes) -> list[int]:
    statuses = []
    rest = written
    while rest:
        # aiohttp answers in the request's version (HTTP/1.0 for a line it cannot read)
        expect(_STATUS_LINE.match(rest) is not None, f"not an HTTP reply: {rest[:40]!r}")
        status = int(rest[9:12])
        statuses.append(status)
        head_end = rest.index(b"\r\n\r\n") + 4
        length = 0
        for line in rest[:head_end].split(b"\r\n"):
            if line.lower().startswith(b"content-length:"):
                length = int(line.split(b":", 1)[1])
        rest = rest[head_end + length :]
    return statuses


async def _settle(connection: GuardedRequestHandler, transport: _Transport) -> None:
    """Let the connection answer what it has: until its output stops growing for a few turns."""
    quiet = 0
    size = len(transport.written)
    for _ in range(2000):
        await asyncio.sleep(0)
        if len(transport.written) == size:
            quiet += 1
            if quiet >= 20:  # a request waiting for the rest of its body stays busy: fine
                return
        else:
            quiet = 0
            size = len(transport.written)
    raise FuzzFailureError(f"the connection kept writing for 2000 loop turns ({connection!r})")


_LOOP: list[asyncio.AbstractEventLoop] = []


def _event_loop() -> asyncio.AbstractEventLoop:
    if not _LOOP:
        _LOOP.append(asyncio.new_event_loop())
    return _LOOP[0]


# ------------------------------------------------------------------------------------- dashboard


class _JsonRequest:
    """What read_body uses of aiohttp's request: the target is our parsing, not aiohttp's."""

    def __init__(self, body: bytes, content_type: str, declared: int | None) -> None:
        self.content_type = content_type
        self.content_length = declared
        self.content = self
        self._body = body

    async def read(self, limit: int) -> bytes:
        return self._body[:limit]


_DASHBOARD_KEYS = ("name", "ra_hours", "dec_deg", "alt_deg", "az_deg", "axis", "rate_deg_s")


def check_dashboard_params(data: bytes, rng: random.Random) -> None:
    """A dashboard command body (JSON) -> Body -> every field read the API makes."""
    declared = rng.choice((None, len(data), len(data) + 1))
    content_type = "application/json" if rng.random() < 0.95 else "text/plain"
    request = _JsonRequest(data, content_type, declared)
    try:
        body = _event_loop().run_until_complete(read_body(typing.cast(web.Request, request)))
    except BadRequestError:
        return
    for key in (*_DASHBOARD_KEYS, "utc", "mode", "latitude_deg"):
        body.has(key)
        for read in ("number", "text", "axis", "mode"):
            try:
                match read:
                    case "number":
                        value = body.number(key, -90.0, 90.0)
                        expect(-90.0 <= value <= 90.0, f"number {value} out of range")
                    case "text":
                        text = body.text(key, max_length=40)
                        expect(0 < len(text) <= 40, f"text {text!r}")
                    case "axis":
                        body.choice(key, MountAxis)
                    case "mode":
                        body.choice(key, TrackingMode)
            except BadRequestError:
                pass


# ---------------------------------------------------------------------------------------- decode


def check_trace_text(data: bytes, rng: random.Random) -> None:
    """``scopelink decode`` input: escaped text, hex or an INDI log -> chunks -> annotations."""
    hex_input = rng.random() < 0.3
    try:
        trace = parse_trace(list(chunks(data, rng)), hex_input=hex_input)
    except TraceInputError as error:
        expect(0 <= error.column <= len(error.line), f"column {error.column} outside its line")
        return
    annotations = annotate(trace, rng.choice(list(Protocol)))
    # docs/decode.md: every byte is in exactly one annotation; untagged traces read in order,
    # tagged ones per direction (a reply may gather bytes from several chunks).
    total = sum(len(chunk.data) for chunk in trace)
    covered = sum(len(annotation.data) for annotation in annotations)
    expect(covered == total, f"annotations hold {covered} bytes of {total}")
    expect(all(0 <= a.offset <= total for a in annotations), "an annotation outside the trace")
    if all(chunk.direction is None for chunk in trace):
        position = 0
        for annotation in annotations:
            if annotation.data:
                expect(annotation.offset == position, f"annotation at {annotation.offset}")
                position += len(annotation.data)
    elif all(chunk.direction is not None for chunk in trace):
        for direction in Direction:
            sent = b"".join(chunk.data for chunk in trace if chunk.direction is direction)
            read = b"".join(a.data for a in annotations if a.direction is direction)
            expect(read == sent, f"{direction.value} bytes annotated as {read!r}, sent {sent!r}")


# ---------------------------------------------------------------------------------------- config


_CONFIG_DIR = Path(tempfile.gettempdir()) / f"scopelink-fuzz-{os.getpid()}"


def check_config(data: bytes, rng: random.Random) -> None:
    """The settings file reader on any bytes: a Config or a ConfigError naming the file."""
    _CONFIG_DIR.mkdir(exist_ok=True)
    path = _CONFIG_DIR / "config.toml"
    path.write_bytes(data)
    try:
        config = load_config(path)
    except ConfigError as error:
        expect(str(path) in str(error), f"the error does not name the file: {error}")
        return
    expect(config.path == path, "config read from the wrong place")


_CONFIG_SEEDS = (
    b'device = "synscan:/dev/ttyUSB0"\n\n[site]\nlatitude = 51.4779\nlongitude = -0.0015\n'
    b"elevation = 46\npressure = 1013.25\ntemperature = 10.5\nhumidity = 0.5\n",
    b"[horizon]\naltitude = 10\nprofile = [[0, 5], [90, 20.5], [180, 0], [270, 15]]\n\n"
    b"[limits]\nmax_altitude = 85\n",
    b'[servers]\nhost = "0.0.0.0"\nalpaca = 11111\nlx200 = false\nstellarium = 0\n'
    b"synscan = 11880\n",
    b'device = "sim"\n[site]\nlatitude = -33.86\nlongitude = 151.2\n[limits]\n',
)


# -------------------------------------------------------------------- devices behind the parsers


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
        _event_loop().run_until_complete(mount.connect())
        alt_az = SimulatedMount(SKY_TRACKER, site=site, clock=SimClock.accelerated(50.0))
        _CONFIG_DIR.mkdir(exist_ok=True)
        azimuth, altitude = alt_az.axes
        bus, _ = memory_pair()
        tracker = SkyTracker(
            altitude=altitude, azimuth=azimuth, clock=alt_az.clock, bus=bus, data_dir=_CONFIG_DIR
        )
        commander = commander_for(alt_az, _CONFIG_DIR)
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
        if isinstance(event, _SYNSCAN_ERRORS):
            continue
        if answered == _DEVICE_COMMANDS_PER_INPUT:
            break
        answered += 1
        reply = _event_loop().run_until_complete(asyncio.wait_for(hand_control.answer(event), 5))
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
        reply = _event_loop().run_until_complete(asyncio.wait_for(session.answer(event), 5))
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
            _event_loop().run_until_complete(device.connect())
            _SETTER_DEVICES.append((device, mount))
    return _SETTER_DEVICES


def _answer(handler: Callable[[Params], object], params: Params) -> int:
    """The ErrorNumber a handler's call would be answered with (0 for success)."""
    try:
        result = handler(params)
        if asyncio.iscoroutine(result):
            _event_loop().run_until_complete(result)
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


# ------------------------------------------------------------------------------- CLI targets


def check_cli_target(data: bytes, rng: random.Random) -> None:
    """A TARGET on the command line (``goto``, ``sync``): a name, or two angles in range."""
    words = data.decode("utf-8", "replace").split(" ")
    altaz = rng.random() < 0.3
    try:
        target = parse_target(words, altaz=altaz)
    except CommandError:
        return
    if isinstance(target, Coordinates):
        # Ranges are the Mount's to check (InvalidValueError names the bound): "82 0" is read.
        expect(isinstance(target.first, float) and isinstance(target.second, float), f"{target}")
    else:
        expect(bool(target.name) and target.name == target.name.strip(), f"{target!r}")


# ----------------------------------------------------------------------------------------- table


def _synscan_server_seeds() -> tuple[bytes, ...]:
    return tuple(synscan.encode_command(command) for command in _SYNSCAN_COMMANDS)


def _synscan_reply_seeds() -> tuple[bytes, ...]:
    return tuple(synscan.encode_reply(reply) for _, reply in _SYNSCAN_EXCHANGES)


TARGETS: tuple[Target, ...] = (
    Target("synscan-server", _synscan_server_seeds(), check_synscan_server, b"#PKTWHRrSsBbe"),
    Target("synscan-client", _synscan_reply_seeds(), check_synscan_client, b"#,0123456789ABCDEF"),
    Target(
        "skytracker-server",
        (*(command.encode() for command in _TRACKER_COMMANDS), b"QL99 05.587 -05.391\rq"),
        check_skytracker_server,
        b"QqSKL\r",
    ),
    Target(
        "skytracker-client",
        tuple(reply.encode() for _, reply in _TRACKER_EXCHANGES),
        check_skytracker_client,
        b"A\x00",
    ),
    Target(
        "commander-server",
        tuple(command.encode() for command in _COMMANDER_COMMANDS),
        check_commander_server,
        b"L\r .+-0123456789",
    ),
    Target(
        "commander-client",
        tuple(reply.encode() for _, reply in _COMMANDER_EXCHANGES),
        check_commander_client,
        b"A\x00",
    ),
    Target("lx200-server", _LX200_COMMANDS, check_lx200_server, b":#\x06*:/+-.0123456789GSMRQ"),
    Target("lx200-skyfi", (b"skyfi?", b"SkyFi:scopelink?", b"skyfi:Mount 1?"), check_skyfi, b":?@"),
    Target(
        "stellarium-server",
        tuple(goto.encode() for goto in _GOTOS) + _STELLARIUM_JUNK,
        check_stellarium_server,
        b"\x00\x14\x18",
    ),
    Target(
        "stellarium-client",
        tuple(position.encode() for position in _POSITIONS) + _STELLARIUM_JUNK,
        check_stellarium_client,
        b"\x00\x14\x18",
    ),
    Target(
        "alpaca-params",
        (
            b"ClientID=1&ClientTransactionID=4294967295",
            b"RightAscension=12.5&Declination=-30.25",
            b"Tracking=True&Connected=false",
            b"Axis=0&Rate=1.5e-1",
            b"Direction=2&Duration=500&clientid=3",
            b"Declination=nan&Azimuth=%2B1e999&Rate=1_0",
        ),
        check_alpaca_params,
        b"=&%+.eE-0123456789",
    ),
    Target("alpaca-http", _HTTP_REQUESTS, check_alpaca_http, b"\r\n: /?=&%0", max_size=1024),
    Target(
        "dashboard-http",
        _DASHBOARD_REQUESTS,
        check_dashboard_http,
        b'\r\n: /?=&%0{}"[]',
        max_size=1024,
    ),
    Target(
        "dashboard-params",
        (
            b'{"name": "M31"}',
            b'{"ra_hours": 5.5875, "dec_deg": -5.391}',
            b'{"alt_deg": 45, "az_deg": 180.5}',
            b'{"axis": "primary", "rate_deg_s": -1.5}',
            b'{"mode": "sidereal"}',
            b'{"utc": "2026-11-23T00:00:00Z", "latitude_deg": 51.5, "longitude_deg": 0}',
        ),
        check_dashboard_params,
        b'{}[]":,0123456789.eE-',
        max_size=4200,  # past read_body's 4096-byte limit
    ),
    Target(
        "decode-trace-text",
        (
            b"-> e\n<- 34AB0500,12CE0500#",
            b"TX: 50 02 11 24\nRX: 06 21 #",
            b"> K\\x80\n< \\x80#",
            b"[DEBUG] CMD <e>\n[DEBUG] RES <34AB0500,12CE0500#>",
            b"CMD <50 03 10 16 00 00 00 02>\nRES <12 34 #>",
            b"CMD: 0XD\nRES: 05.500 -20.250",
            b"PC: Q\nST: A\nPC: L99 05.587 -05.391\\r\nSC: A",
        ),
        check_trace_text,
        b"\\\n<->:xrn0 ",
        max_size=512,
    ),
    Target(
        "synscan-device",
        _synscan_server_seeds(),
        check_synscan_device,
        b"#PKTWHRrSsBbe",
        max_size=64,
        share=0.05,
    ),
    Target(
        "skytracker-device",
        (*(command.encode() for command in _TRACKER_COMMANDS), b"QL99 05.588 -05.391\rOR\rq"),
        check_skytracker_device,
        b"QqSKL\r",
        max_size=64,
        share=0.25,
    ),
    Target(
        "lx200-device",
        _LX200_COMMANDS,
        check_lx200_device,
        b":#\x06*:/+-.0123456789GSMRQ",
        max_size=64,
        share=0.05,
    ),
    Target(
        "cli-target",
        (
            b"05:35:17 -05:23:28",
            b"5.5 -5.4",
            b"5h35m17s -5\xc2\xb023'28\"",
            b"5 35 17 -5 23 28",
            b"M31",
        ),
        check_cli_target,
        b" :.+-hmsd0123456789'\"",
    ),
    Target("config", _CONFIG_SEEDS, check_config, b'[]{}=."\n#0123456789-', max_size=6000),
    Target(
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
    ),
)


def target_named(name: str) -> Target:
    for target in TARGETS:
        if target.name == name:
            return target
    raise KeyError(f"no fuzz target {name!r} (known: {', '.join(t.name for t in TARGETS)})")
