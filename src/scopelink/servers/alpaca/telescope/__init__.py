"""The ASCOM ITelescopeV4 device: :class:`TelescopeDevice` and its member groups.

``device`` joins the groups into one member table; ``session`` is what they share (the mount,
the configuration, the client's connection). One module per ASCOM group: ``common``,
``capabilities``, ``position``, ``tracking``, ``slewing``, ``parking``, ``motion``, ``site``.
"""

from scopelink.servers.alpaca.telescope.common import INTERFACE_VERSION
from scopelink.servers.alpaca.telescope.config import EquatorialSystem, TelescopeConfig
from scopelink.servers.alpaca.telescope.device import TelescopeDevice
from scopelink.servers.alpaca.telescope.member import Member
from scopelink.servers.alpaca.telescope.site import format_utc, parse_utc
from scopelink.servers.alpaca.telescope.slewing import MAX_SETTLE_TIME_S
from scopelink.servers.alpaca.telescope.tracking import DriveRate

__all__ = [
    "INTERFACE_VERSION",
    "MAX_SETTLE_TIME_S",
    "DriveRate",
    "EquatorialSystem",
    "Member",
    "TelescopeConfig",
    "TelescopeDevice",
    "format_utc",
    "parse_utc",
]
