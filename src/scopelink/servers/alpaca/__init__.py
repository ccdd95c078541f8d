"""ASCOM Alpaca: the telescope device API, management API, setup pages and UDP discovery.

Start it with :class:`AlpacaServer` (an async context manager); see ``docs/alpaca.md``.
"""

from scopelink.servers.alpaca.discovery import DISCOVERY_MESSAGE, DISCOVERY_PORT
from scopelink.servers.alpaca.errors import AlpacaError, BadRequest, ErrorNumber
from scopelink.servers.alpaca.server import ALPACA_PORT, MAX_REQUEST_BYTES, AlpacaServer
from scopelink.servers.alpaca.telescope import (
    INTERFACE_VERSION,
    DriveRate,
    EquatorialSystem,
    TelescopeConfig,
    TelescopeDevice,
)

__all__ = [
    "ALPACA_PORT",
    "DISCOVERY_MESSAGE",
    "DISCOVERY_PORT",
    "INTERFACE_VERSION",
    "MAX_REQUEST_BYTES",
    "AlpacaError",
    "AlpacaServer",
    "BadRequest",
    "DriveRate",
    "EquatorialSystem",
    "ErrorNumber",
    "TelescopeConfig",
    "TelescopeDevice",
]
