"""The ASCOM ITelescopeV4 device over any :class:`~scopelink.mount.Mount`.

Every member of the interface is in :attr:`TelescopeDevice.members`, keyed by its lower-case
URL name, with a handler for GET (properties), PUT (methods and setters) or both. The members
come in the groups ASCOM itself uses, one module each (the table in ``docs/alpaca.md``, "Where
the code is", names the module of every member). Reads come from the mount's state cache
(``mount.state``), never from the wire; commands go through the Mount's public, limit-checked
methods. What the mount cannot do answers NotImplemented (0x400).
"""

from __future__ import annotations

from dataclasses import replace

from scopelink.mount import Mount
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope.capabilities import CapabilityMembers
from scopelink.servers.alpaca.telescope.common import CommonMembers
from scopelink.servers.alpaca.telescope.config import TelescopeConfig
from scopelink.servers.alpaca.telescope.member import Handler, Member, MemberGroup
from scopelink.servers.alpaca.telescope.motion import MotionMembers
from scopelink.servers.alpaca.telescope.parking import ParkingMembers
from scopelink.servers.alpaca.telescope.position import PositionMembers
from scopelink.servers.alpaca.telescope.session import TelescopeSession
from scopelink.servers.alpaca.telescope.site import SiteMembers
from scopelink.servers.alpaca.telescope.slewing import SlewingMembers
from scopelink.servers.alpaca.telescope.tracking import TrackingMembers

__all__ = ["TelescopeDevice"]

_FRESH_READS = {
    "altitude": True,
    "azimuth": True,
    "rightascension": True,
    "declination": True,
    "sideofpier": True,
    "atpark": False,
    "slewing": False,
    "tracking": False,
    "ispulseguiding": False,
}
"""Reads of the device's state, refused while it is not current: True for the position's age,
False for the state flags' (docs/alpaca.md, "Lost and stalled devices")."""


class TelescopeDevice:
    """ASCOM ``telescope/0`` over ``mount``: one object per served device."""

    def __init__(self, mount: Mount, config: TelescopeConfig | None = None) -> None:
        self.mount = mount
        self.config = config or TelescopeConfig()
        self.session = TelescopeSession(mount, self.config)
        self.members: dict[str, Member] = self._member_table()

    @property
    def connected(self) -> bool:
        """Whether an Alpaca client has connected and the mount itself is connected."""
        return self.session.connected

    async def connect(self) -> None:
        """Connect the mount if it is not already (other front ends may share it)."""
        await self.session.connect()

    def disconnect(self) -> None:
        """Forget the Alpaca connection; the mount stays connected for other front ends."""
        self.session.disconnect()

    def require_connected(self) -> None:
        """0x407 unless an Alpaca client has connected and the mount's link is up."""
        self.session.require_connected()

    async def close(self) -> None:
        """Stop a Connect still running (the server is shutting down)."""
        await self.session.close()

    def _member_table(self) -> dict[str, Member]:
        session = self.session
        groups: tuple[MemberGroup, ...] = (
            CommonMembers(session),
            CapabilityMembers(session),
            PositionMembers(session),
            TrackingMembers(session),
            SlewingMembers(session),
            ParkingMembers(session),
            MotionMembers(session),
            SiteMembers(session),
        )
        table: dict[str, Member] = {}
        for group in groups:
            members = group.members()
            assert table.keys().isdisjoint(members), "a member is in two groups"
            table |= members
        for name, position in _FRESH_READS.items():
            if name == "sideofpier" and not self.mount.capabilities.can_report_pier_side:
                continue  # not implemented, however fresh
            member = table[name]
            assert member.get is not None
            table[name] = replace(member, get=self._fresh_read(member.get, position=position))
        return table

    def _fresh_read(self, read: Handler, *, position: bool) -> Handler:
        """``read``, refused while the state it reports is not current (see require_fresh)."""

        def handler(params: Params) -> object:
            self.session.require_fresh(position=position)
            return read(params)

        return handler
