"""Planetarium protocol targets: LX200 (and SkyFi discovery) and Stellarium, both sides."""

from __future__ import annotations

import random
import typing
from collections.abc import Sequence

from bench.fuzz_targets.base import (
    Target,
    checked_events,
    expect,
)
from scopelink.protocol import lx200, stellarium

LX200_COMMANDS = (
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
LX200_TOKENS = b":#\x06*:/+-.0123456789GSMRQ"
_LX200_EVENTS = (
    *typing.get_args(lx200.AnyCommand),
    lx200.UnknownCommand,
    lx200.MalformedCommand,
    lx200.StrayBytes,
)


def _lx200_events(
    connection: lx200.LX200ServerConnection, data: bytes, rng: random.Random
) -> list[object]:
    return checked_events(connection, data, rng, lx200.NEED_DATA, _LX200_EVENTS)


def check_lx200_server(data: bytes, rng: random.Random) -> None:
    """The handset side's command framing and parsing; any garbage is ended by a ``#``."""
    connection = lx200.LX200ServerConnection()
    _lx200_events(connection, data, rng)
    _lx200_events(connection, b"#", rng)
    expect(not connection.pending, "a '#' did not end the garbage")
    valid = [rng.choice(LX200_COMMANDS) for _ in range(rng.randint(1, 3))]
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
        return checked_events(connection, stream, rng, stellarium.NEED_DATA, _STELLARIUM_EVENTS)

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


TARGETS: tuple[Target, ...] = (
    Target("lx200-server", LX200_COMMANDS, check_lx200_server, LX200_TOKENS),
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
)
