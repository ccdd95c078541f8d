"""Slewing and syncing: the target, SlewSettleTime, SlewTo*, SyncTo* and AbortSlew.

Every command goes through the Mount's public, limit-checked methods. A synchronous slew waits
on the state cache for the slew's end, then SlewSettleTime.
"""

from __future__ import annotations

import asyncio

from scopelink.astro import observed_to_j2000
from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope.member import Member, MemberGroup
from scopelink.servers.alpaca.telescope.session import TelescopeSession

__all__ = ["MAX_SETTLE_TIME_S", "SlewingMembers"]

MAX_SETTLE_TIME_S = 300
"""Longest SlewSettleTime accepted (seconds): a longer one holds every synchronous slew for
that long, which is a typo (milliseconds?) rather than a mount's settling."""

_SLEW_POLL_S = 0.05
"""How often a synchronous slew looks at the state cache for the end of the slew."""


def _target(value: float | None, what: str) -> float:
    if value is None:
        raise AlpacaError(ErrorNumber.VALUE_NOT_SET, f"{what} has not been set")
    return value


def _coordinates(params: Params) -> tuple[float, float]:
    ra = params.number("RightAscension", 0.0, 24.0) % 24.0
    dec = params.number("Declination", -90.0, 90.0)
    return ra, dec


def _horizontal(params: Params) -> tuple[float, float]:
    """(altitude, azimuth) of an alt/az slew or sync (a bad Azimuth is named first)."""
    azimuth = params.number("Azimuth", 0.0, 360.0) % 360.0
    altitude = params.number("Altitude", -90.0, 90.0)
    return altitude, azimuth


class SlewingMembers(MemberGroup):
    """Slews, syncs and their target, in the configured equatorial frame or in alt/az."""

    def __init__(self, session: TelescopeSession) -> None:
        super().__init__(session)
        self._target_ra: float | None = None
        self._target_dec: float | None = None
        self._settle_time_s = 0

    def members(self) -> dict[str, Member]:
        return {
            "slewsettletime": Member(get=lambda _: self._settle_time_s, put=self._put_settle_time),
            "targetrightascension": Member(
                get=lambda _: _target(self._target_ra, "TargetRightAscension"),
                put=self._put_target_ra,
            ),
            "targetdeclination": Member(
                get=lambda _: _target(self._target_dec, "TargetDeclination"),
                put=self._put_target_dec,
            ),
            # An abort is tried while the link is down too (the driver tries it, or owes it).
            "abortslew": Member(put=self._abort_slew, needs_connection=False),
            "slewtoaltaz": Member(put=self._slew_to_altaz),
            "slewtoaltazasync": Member(put=self._slew_to_altaz_async),
            "slewtocoordinates": Member(put=self._slew_to_coordinates),
            "slewtocoordinatesasync": Member(put=self._slew_to_coordinates_async),
            "slewtotarget": Member(put=self._slew_to_target),
            "slewtotargetasync": Member(put=self._slew_to_target_async),
            "synctoaltaz": Member(put=self._sync_to_altaz),
            "synctocoordinates": Member(put=self._sync_to_coordinates),
            "synctotarget": Member(put=self._sync_to_target),
        }

    # --- the target and the settle time ----------------------------------------------------------

    def _put_target_ra(self, params: Params) -> None:
        self._target_ra = params.number("TargetRightAscension", 0.0, 24.0) % 24.0

    def _put_target_dec(self, params: Params) -> None:
        self._target_dec = params.number("TargetDeclination", -90.0, 90.0)

    def _put_settle_time(self, params: Params) -> None:
        self._settle_time_s = params.integer("SlewSettleTime", 0, MAX_SETTLE_TIME_S)

    def _targets(self) -> tuple[float, float]:
        ra = _target(self._target_ra, "TargetRightAscension")
        dec = _target(self._target_dec, "TargetDeclination")
        return ra, dec

    # --- slews -----------------------------------------------------------------------------------

    async def _goto_radec(self, ra_hours: float, dec_deg: float) -> None:
        session = self.session
        session.require_unparked()
        ra_j2000, dec_j2000 = session.to_j2000(ra_hours % 24.0, dec_deg)
        started = session.mount.now()
        await session.call(session.mount.goto_equatorial(ra_j2000, dec_j2000))
        session.slew_started_at = started

    async def _slew_to_altaz_async(self, params: Params) -> None:
        altitude, azimuth = _horizontal(params)
        session = self.session
        session.require_unparked()
        session.require_tracking_off("SlewToAltAz")
        started = session.mount.now()
        await session.call(session.mount.goto_horizontal(altitude, azimuth))
        session.slew_started_at = started

    async def _slew_to_coordinates_async(self, params: Params) -> None:
        ra, dec = _coordinates(params)
        self._target_ra, self._target_dec = ra, dec
        await self._goto_radec(ra, dec)

    async def _slew_to_coordinates(self, params: Params) -> None:
        await self._slew_to_coordinates_async(params)
        await self._wait_for_slew()

    async def _slew_to_target_async(self, _: Params) -> None:
        await self._goto_radec(*self._targets())

    async def _slew_to_target(self, params: Params) -> None:
        await self._slew_to_target_async(params)
        await self._wait_for_slew()

    async def _slew_to_altaz(self, params: Params) -> None:
        await self._slew_to_altaz_async(params)
        await self._wait_for_slew()

    async def _wait_for_slew(self) -> None:
        """Return once the state cache says the slew has ended, then wait SlewSettleTime."""
        session = self.session
        timeout_s = session.config.slew_timeout_s
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout_s
        while session.slewing or not session.mount.state.connected:
            if not session.mount.state.connected:  # the end of the slew cannot be seen
                session.require_fresh(position=False)
            if loop.time() > deadline:
                raise AlpacaError(
                    ErrorNumber.DRIVER_ERROR, f"the slew has not ended within {timeout_s:g} s"
                )
            await asyncio.sleep(_SLEW_POLL_S)
        if self._settle_time_s:
            await asyncio.sleep(self._settle_time_s)

    async def _abort_slew(self, _: Params) -> None:
        session = self.session
        if not session.client_connected:
            session.require_connected()
        session.require_unparked()
        await session.call(session.mount.abort())
        session.slew_started_at = None

    # --- syncs -----------------------------------------------------------------------------------

    async def _sync(self, ra_hours: float, dec_deg: float) -> None:
        session = self.session
        session.require_unparked()
        if not session.mount.capabilities.can_sync:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot sync")
        ra_j2000, dec_j2000 = session.to_j2000(ra_hours, dec_deg)
        await session.call(session.mount.sync_equatorial(ra_j2000, dec_j2000))

    async def _sync_to_coordinates(self, params: Params) -> None:
        ra, dec = _coordinates(params)
        self._target_ra, self._target_dec = ra, dec
        await self._sync(ra, dec)

    async def _sync_to_target(self, _: Params) -> None:
        await self._sync(*self._targets())

    async def _sync_to_altaz(self, params: Params) -> None:
        altitude, azimuth = _horizontal(params)
        session = self.session
        mount = session.mount
        if not mount.capabilities.can_sync:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot sync")
        session.require_unparked()
        session.require_tracking_off("SyncToAltAz")
        ra, dec = observed_to_j2000(altitude, azimuth, mount.now(), mount.site)
        await session.call(mount.sync_equatorial(ra, dec))
