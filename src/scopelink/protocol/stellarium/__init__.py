"""Stellarium's binary telescope-control protocol (TCP, version 1.0), sans-IO.

- `messages`: :class:`GotoMessage` (client -> server), :class:`CurrentPosition` (server ->
  client) and the RA/Dec wire units;
- `connection`: :class:`StellariumServerConnection` and :class:`StellariumClientConnection`,
  incremental framing by the LENGTH field.
"""

from scopelink.protocol.stellarium.connection import (
    MAX_MESSAGE_LENGTH,
    NEED_DATA,
    BadLength,
    NeedData,
    SkippedMessage,
    StellariumClientConnection,
    StellariumServerConnection,
)
from scopelink.protocol.stellarium.messages import (
    CURRENT_POSITION_LENGTH,
    GOTO_LENGTH,
    CurrentPosition,
    GotoMessage,
    dec_from_wire,
    dec_to_wire,
    ra_from_wire,
    ra_to_wire,
)

__all__ = [
    "CURRENT_POSITION_LENGTH",
    "GOTO_LENGTH",
    "MAX_MESSAGE_LENGTH",
    "NEED_DATA",
    "BadLength",
    "CurrentPosition",
    "GotoMessage",
    "NeedData",
    "SkippedMessage",
    "StellariumClientConnection",
    "StellariumServerConnection",
    "dec_from_wire",
    "dec_to_wire",
    "ra_from_wire",
    "ra_to_wire",
]
