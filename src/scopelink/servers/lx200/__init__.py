"""The LX200 server: SkySafari, Stellarium and INDI drive any Mount as a Meade handset.

- `config`: :class:`LX200Config` (identity, ``:CM#`` reply style, rates) and :class:`SyncReply`;
- `device`: :class:`LX200Handset` / :class:`LX200Session`, each command as calls on the mount;
- `server`: :class:`LX200Server` on TCP 4030 and/or a pty;
- `skyfi`: :class:`SkyFiResponder`, SkySafari's UDP 4031 auto-detect.
"""

from scopelink.servers.lx200.config import DEFAULT_RATES_SIDEREAL, LX200Config, SyncReply
from scopelink.servers.lx200.device import LX200Handset, LX200Session
from scopelink.servers.lx200.server import DEFAULT_PORT, PARTIAL_COMMAND_TIMEOUT_S, LX200Server
from scopelink.servers.lx200.skyfi import SkyFiResponder

__all__ = [
    "DEFAULT_PORT",
    "DEFAULT_RATES_SIDEREAL",
    "PARTIAL_COMMAND_TIMEOUT_S",
    "LX200Config",
    "LX200Handset",
    "LX200Server",
    "LX200Session",
    "SkyFiResponder",
    "SyncReply",
]
