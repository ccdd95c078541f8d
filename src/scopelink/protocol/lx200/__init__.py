"""The Meade LX200 command set (the subset planetarium programs use), sans-IO.

- `angles`: the sexagesimal forms on the wire, both precisions;
- `commands`: typed commands, :func:`parse_command`, :func:`encode_command`, reply shapes;
- `replies`: the handset's replies as bytes;
- `connection`: :class:`LX200ServerConnection`, framing ``:...#`` commands and the ACK byte;
- `skyfi`: SkySafari's SkyFi discovery datagrams.
"""

from scopelink.protocol.lx200.angles import (
    format_altitude,
    format_azimuth,
    format_dec,
    format_ra,
    parse_sexagesimal,
)
from scopelink.protocol.lx200.commands import (
    ACK_BYTE,
    Ack,
    AnyCommand,
    Direction,
    Get,
    GotoTarget,
    Halt,
    MalformedCommand,
    Move,
    PulseGuide,
    Query,
    ReplyKind,
    SetLatitude,
    SetLocalDate,
    SetLocalTime,
    SetLongitude,
    SetRate,
    SetTargetDec,
    SetTargetRA,
    SetUtcOffset,
    SlewRate,
    SyncTarget,
    TogglePrecision,
    UnknownCommand,
    encode_command,
    parse_command,
    reply_kind,
)
from scopelink.protocol.lx200.connection import (
    MAX_COMMAND_LENGTH,
    NEED_DATA,
    LX200ServerConnection,
    NeedData,
    StrayBytes,
)
from scopelink.protocol.lx200.replies import (
    DATE_SET_REPLY,
    SlewRefusal,
    boolean_reply,
    slew_reply,
    text_reply,
)
from scopelink.protocol.lx200.skyfi import SKYFI_PORT, SkyFiQuery, parse_skyfi_query, skyfi_reply

__all__ = [
    "ACK_BYTE",
    "DATE_SET_REPLY",
    "MAX_COMMAND_LENGTH",
    "NEED_DATA",
    "SKYFI_PORT",
    "Ack",
    "AnyCommand",
    "Direction",
    "Get",
    "GotoTarget",
    "Halt",
    "LX200ServerConnection",
    "MalformedCommand",
    "Move",
    "NeedData",
    "PulseGuide",
    "Query",
    "ReplyKind",
    "SetLatitude",
    "SetLocalDate",
    "SetLocalTime",
    "SetLongitude",
    "SetRate",
    "SetTargetDec",
    "SetTargetRA",
    "SetUtcOffset",
    "SkyFiQuery",
    "SlewRate",
    "SlewRefusal",
    "StrayBytes",
    "SyncTarget",
    "TogglePrecision",
    "UnknownCommand",
    "boolean_reply",
    "encode_command",
    "format_altitude",
    "format_azimuth",
    "format_dec",
    "format_ra",
    "parse_command",
    "parse_sexagesimal",
    "parse_skyfi_query",
    "reply_kind",
    "skyfi_reply",
    "slew_reply",
    "text_reply",
]
