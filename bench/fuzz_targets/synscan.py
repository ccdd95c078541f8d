"""SynScan targets: the hand control's command parser and the driver's reply parser."""

from __future__ import annotations

import random

from bench.fuzz_targets.base import (
    FuzzFailureError,
    Target,
    chunks,
    expect,
    parsed_in_chunks,
    progress_guard,
)
from scopelink.protocol import synscan

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
SYNSCAN_COMMAND_ERRORS = (synscan.UnknownCommand, synscan.MalformedCommand)
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
            progress_guard(count, len(data))
            if isinstance(event, SYNSCAN_COMMAND_ERRORS):
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


SYNSCAN_COMMAND_SEEDS = tuple(synscan.encode_command(command) for command in _SYNSCAN_COMMANDS)
"""Every command of the exchanges, encoded (the device target's seeds too)."""
SYNSCAN_COMMAND_TOKENS = b"#PKTWHRrSsBbe"
_REPLY_SEEDS = tuple(synscan.encode_reply(reply) for _, reply in _SYNSCAN_EXCHANGES)


TARGETS: tuple[Target, ...] = (
    Target("synscan-server", SYNSCAN_COMMAND_SEEDS, check_synscan_server, SYNSCAN_COMMAND_TOKENS),
    Target("synscan-client", _REPLY_SEEDS, check_synscan_client, b"#,0123456789ABCDEF"),
)
