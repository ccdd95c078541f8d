"""Sky Tracker and Sky Commander targets: both firmwares' command parsers and both reply readers."""

from __future__ import annotations

import random

from bench.fuzz_targets.base import (
    Target,
    chunks,
    expect,
    parsed_in_chunks,
    progress_guard,
)
from scopelink.protocol import skytracker
from scopelink.protocol.skytracker import commander_messages
from scopelink.protocol.skytracker import messages as tracker_messages

TRACKER_COMMANDS: tuple[skytracker.TrackerCommand, ...] = (
    *(
        command
        for command in tracker_messages.SINGLE_BYTE_COMMANDS.values()
        if not isinstance(command, skytracker.RequestBus | skytracker.ReleaseBus)
    ),
    skytracker.SetCalibration(1.5, 2.25),
    skytracker.SetGuideSpeed(15, 30),
)
TRACKER_TOKENS = b"QqSKL\r"
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
        progress_guard(len(events), fed)
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
            progress_guard(count, len(data))
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
    valid = [rng.choice(TRACKER_COMMANDS) for _ in range(rng.randint(1, 3))]
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


TARGETS: tuple[Target, ...] = (
    Target(
        "skytracker-server",
        (*(command.encode() for command in TRACKER_COMMANDS), b"QL99 05.587 -05.391\rq"),
        check_skytracker_server,
        TRACKER_TOKENS,
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
)
