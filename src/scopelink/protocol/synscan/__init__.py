"""Sky-Watcher SynScan hand control serial protocol (V3/V4), sans-IO, for both ends of the link.

One concern per module:

- `message`: the shape of a command and a reply, and what reading a reply finds;
- `values`: axes, frames, tracking modes, dialects, range checks;
- `angles`: revolution fractions, rate bytes, 24-bit positions;
- `scanning`: the incremental, byte-by-byte reply reader and hex angle pairs;
- `replies`: the reply classes;
- `commands`: the command classes (letters, frame lengths, encoding, decoding, reply shape);
- `passthrough`: the ``P`` + 7 bytes commands;
- `tables`: `AnyCommand`, `AnyReply` and the tables derived from the classes;
- `handler`: `CommandHandler`, one method per command, and `dispatch`;
- `parser`: length-framed parsing of the command stream (`CommandParser`);
- `events`: the error events;
- `connection`: `SynScanClientConnection` (PC side) and `SynScanServerConnection` (hand-control
  side)."""

from scopelink.protocol.base import NEED_DATA, LocalProtocolError, NeedData
from scopelink.protocol.synscan.commands import (
    CancelGoto,
    Echo,
    GetAzAlt,
    GetLocation,
    GetModel,
    GetPointingState,
    GetRaDec,
    GetTime,
    GetTrackingMode,
    GetVersion,
    GotoAzAlt,
    GotoRaDec,
    IsAligned,
    IsGotoInProgress,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SyncRaDec,
)
from scopelink.protocol.synscan.connection import (
    ClientState,
    SynScanClientConnection,
    SynScanServerConnection,
)
from scopelink.protocol.synscan.events import (
    ClientError,
    MalformedCommand,
    MalformedReply,
    ServerError,
    UnexpectedData,
    UnknownCommand,
)
from scopelink.protocol.synscan.handler import CommandHandler, dispatch
from scopelink.protocol.synscan.message import (
    Command,
    Complete,
    Mismatch,
    Reply,
    ReplyShape,
    ScanResult,
)
from scopelink.protocol.synscan.parser import CommandParser, ParsedCommand
from scopelink.protocol.synscan.passthrough import (
    FixedRateSlew,
    GetDeviceVersion,
    Passthrough,
    PassthroughCommand,
    SetAxisPosition,
    SlowGoto,
    VariableRateSlew,
    passthrough_command,
)
from scopelink.protocol.synscan.replies import (
    Ack,
    Aligned,
    DateTime,
    DeviceVersion,
    EchoReply,
    GotoInProgress,
    Location,
    Model,
    PassthroughFailed,
    PassthroughReply,
    PointingState,
    Position,
    TrackingModeReply,
    Version,
)
from scopelink.protocol.synscan.tables import (
    COMMANDS,
    FRAME_LENGTHS,
    REPLIES,
    AnyCommand,
    AnyReply,
    ReplyError,
    decode_command_frame,
    encode_command,
    encode_reply,
    frame_length,
    parse_reply,
    reply_fits,
    reply_shape,
    scan_reply,
)
from scopelink.protocol.synscan.values import (
    Axis,
    Frame,
    PointingSide,
    Tracking,
    VersionDialect,
)

__all__ = [
    "COMMANDS",
    "FRAME_LENGTHS",
    "NEED_DATA",
    "REPLIES",
    "Ack",
    "Aligned",
    "AnyCommand",
    "AnyReply",
    "Axis",
    "CancelGoto",
    "ClientError",
    "ClientState",
    "Command",
    "CommandHandler",
    "CommandParser",
    "Complete",
    "DateTime",
    "DeviceVersion",
    "Echo",
    "EchoReply",
    "FixedRateSlew",
    "Frame",
    "GetAzAlt",
    "GetDeviceVersion",
    "GetLocation",
    "GetModel",
    "GetPointingState",
    "GetRaDec",
    "GetTime",
    "GetTrackingMode",
    "GetVersion",
    "GotoAzAlt",
    "GotoInProgress",
    "GotoRaDec",
    "IsAligned",
    "IsGotoInProgress",
    "LocalProtocolError",
    "Location",
    "MalformedCommand",
    "MalformedReply",
    "Mismatch",
    "Model",
    "NeedData",
    "ParsedCommand",
    "Passthrough",
    "PassthroughCommand",
    "PassthroughFailed",
    "PassthroughReply",
    "PointingSide",
    "PointingState",
    "Position",
    "Reply",
    "ReplyError",
    "ReplyShape",
    "ScanResult",
    "ServerError",
    "SetAxisPosition",
    "SetLocation",
    "SetTime",
    "SetTrackingMode",
    "SlowGoto",
    "SynScanClientConnection",
    "SynScanServerConnection",
    "SyncRaDec",
    "Tracking",
    "TrackingModeReply",
    "UnexpectedData",
    "UnknownCommand",
    "VariableRateSlew",
    "Version",
    "VersionDialect",
    "decode_command_frame",
    "dispatch",
    "encode_command",
    "encode_reply",
    "frame_length",
    "parse_reply",
    "passthrough_command",
    "reply_fits",
    "reply_shape",
    "scan_reply",
]
