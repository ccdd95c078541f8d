"""Parking and homing: Park, Unpark, SetPark and FindHome (no mount here searches for home)."""

from __future__ import annotations

import logging

from scopelink.mount import Mount, MountError, ParkPosition
from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber, from_mount_error
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope.member import Member, MemberGroup, not_implemented

__all__ = ["ParkingMembers"]

logger = logging.getLogger(__name__)


class ParkingMembers(MemberGroup):
    """Park (a slew: Slewing is true until it has landed), Unpark and SetPark."""

    def members(self) -> dict[str, Member]:
        return {
            "park": Member(put=self._park),
            "unpark": Member(put=self._unpark),
            "setpark": Member(put=self._set_park),
            "findhome": Member(put=not_implemented("FindHome")),
        }

    async def _park(self, _: Params) -> None:
        session = self.session
        mount = session.mount
        if not mount.capabilities.can_park:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot park")
        if mount.state.parked:
            return  # ASCOM: Park when already parked does nothing
        started = mount.now()
        await session.call(mount.park())
        session.slew_started_at = started

    async def _unpark(self, _: Params) -> None:
        mount = self.session.mount
        if not mount.capabilities.can_park:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot unpark")
        await self.session.call(self._unpark_and_say(mount))

    @staticmethod
    async def _unpark_and_say(mount: Mount) -> None:
        """Unpark; what was done with the park record is logged (Alpaca has no place for it)."""
        resume = await mount.unpark()
        logger.info("Unpark: %s", resume.message)

    def _set_park(self, _: Params) -> None:
        session = self.session
        mount = session.mount
        if not mount.capabilities.can_set_park:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount's park position is fixed")
        state = mount.state
        alt = session.known(state.alt_deg, "position")
        az = session.known(state.az_deg, "position")
        try:  # refused outside the limits: every later Park would drive the mount there
            mount.park_position = ParkPosition(alt, az % 360.0)
        except MountError as error:
            raise from_mount_error(error) from error
