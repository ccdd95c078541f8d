"""Tracking and rates: Tracking, TrackingRate, TrackingRates, the offset and guide rates."""

from __future__ import annotations

import enum
from collections.abc import Awaitable, Callable

from scopelink.mount import AlignmentMode, Mount, TrackingMode
from scopelink.mount.rates import GuideRates, ra_rate_from_ascom, ra_rate_to_ascom
from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope.member import Member, MemberGroup, not_implemented
from scopelink.servers.alpaca.telescope.session import TelescopeSession

__all__ = ["DriveRate", "TrackingMembers", "supported_drive_rates"]


class DriveRate(enum.IntEnum):
    """ASCOM ``DriveRates``."""

    SIDEREAL = 0
    LUNAR = 1
    SOLAR = 2
    KING = 3


_DRIVE_RATE_OF_MODE = {
    TrackingMode.SIDEREAL: DriveRate.SIDEREAL,
    TrackingMode.ALT_AZ: DriveRate.SIDEREAL,
    TrackingMode.PEC: DriveRate.SIDEREAL,
    TrackingMode.LUNAR: DriveRate.LUNAR,
    TrackingMode.SOLAR: DriveRate.SOLAR,
    TrackingMode.KING: DriveRate.KING,
}


def mode_for(mount: Mount, rate: DriveRate) -> TrackingMode | None:
    """The tracking mode that drives ``mount`` at ``rate`` (None: it has none)."""
    modes = mount.capabilities.tracking_modes
    if rate is DriveRate.SIDEREAL:
        # An alt-az mount follows the stars on both axes: its own mode (SynScan's "alt-az").
        preferred = (
            (TrackingMode.ALT_AZ, TrackingMode.SIDEREAL)
            if mount.capabilities.alignment_mode is AlignmentMode.ALT_AZ
            else (TrackingMode.SIDEREAL, TrackingMode.PEC, TrackingMode.ALT_AZ)
        )
        for mode in preferred:
            if mode in modes:
                return mode
        return None
    if rate is DriveRate.LUNAR:
        return TrackingMode.LUNAR
    if rate is DriveRate.SOLAR:
        return TrackingMode.SOLAR
    return TrackingMode.KING


def supported_drive_rates(mount: Mount) -> list[DriveRate]:
    """The ASCOM drive rates ``mount`` can track at (its TrackingRates)."""
    modes = mount.capabilities.tracking_modes
    return [rate for rate in DriveRate if mode_for(mount, rate) in modes]


class TrackingMembers(MemberGroup):
    """Tracking on/off at the selected drive rate; the rates the mount cannot change."""

    def __init__(self, session: TelescopeSession) -> None:
        super().__init__(session)
        self._drive_rate = DriveRate.SIDEREAL
        """The selected TrackingRate, remembered while tracking is off."""

    def members(self) -> dict[str, Member]:
        mount = self.session.mount
        ni = not_implemented
        return {
            "tracking": Member(
                get=lambda _: mount.state.tracking is not TrackingMode.OFF,
                put=self._put_tracking,
            ),
            "trackingrate": Member(get=self._tracking_rate, put=self._put_tracking_rate),
            "trackingrates": Member(
                get=lambda _: [int(rate) for rate in supported_drive_rates(mount)],
                needs_connection=False,
            ),
            "rightascensionrate": Member(
                get=lambda _: ra_rate_to_ascom(mount.tracking_rates.ra_arcsec_per_s),
                put=self._put_ra_rate,
            ),
            "declinationrate": Member(
                get=lambda _: mount.tracking_rates.dec_arcsec_per_s, put=self._put_dec_rate
            ),
            "guideratedeclination": Member(
                get=lambda _: self._guide_rates()[1],
                put=self._put_guide_rate("GuideRateDeclination", 1)
                if isinstance(mount, GuideRates)
                else ni("GuideRateDeclination"),
            ),
            "guideraterightascension": Member(
                get=lambda _: self._guide_rates()[0],
                put=self._put_guide_rate("GuideRateRightAscension", 0)
                if isinstance(mount, GuideRates)
                else ni("GuideRateRightAscension"),
            ),
        }

    def _tracking_rate(self, _: Params) -> int:
        tracking = self.session.mount.state.tracking
        return int(_DRIVE_RATE_OF_MODE.get(tracking, self._drive_rate))

    def _guide_rates(self) -> tuple[float, float]:
        """(RA, Dec) in °/s: a driver whose guide rates can be set (GuideRates) says both; a
        mount that knows one rate (the simulator) says it for both."""
        mount = self.session.mount
        if isinstance(mount, GuideRates):
            return mount.guide_rates_deg_s
        rate = getattr(mount, "guide_rate_deg_s", None)
        if not isinstance(rate, float):
            raise AlpacaError(
                ErrorNumber.NOT_IMPLEMENTED, "this mount does not report a guide rate"
            )
        return rate, rate

    def _put_guide_rate(self, name: str, index: int) -> Callable[[Params], Awaitable[None]]:
        """The setter of one guide rate (°/s), the other kept; stored on the mount and used by
        PulseGuide."""

        async def put(params: Params) -> None:
            mount = self.session.mount
            assert isinstance(mount, GuideRates)
            rates = list(mount.guide_rates_deg_s)
            rates[index] = params.number(name)
            await self.session.call(mount.set_guide_rates(rates[0], rates[1]))

        return put

    async def _put_tracking(self, params: Params) -> None:
        on = params.boolean("Tracking")
        mount = self.session.mount
        mode = mode_for(mount, self._drive_rate) if on else TrackingMode.OFF
        if mode is None:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot track")
        await self.session.call(mount.set_tracking(mode))

    async def _put_ra_rate(self, params: Params) -> None:
        """RightAscensionRate, s of RA per sidereal s, an offset from sidereal: ASCOM refuses it
        (InvalidOperation) at another TrackingRate."""
        value = ra_rate_from_ascom(params.number("RightAscensionRate"))
        mount = self.session.mount
        if value != 0.0 and self._tracking_rate(params) != DriveRate.SIDEREAL:
            raise AlpacaError(
                ErrorNumber.INVALID_OPERATION,
                "RightAscensionRate is an offset from the sidereal rate: set TrackingRate to "
                "sidereal first",
            )
        await self.session.call(
            mount.set_tracking_rates(value, mount.tracking_rates.dec_arcsec_per_s)
        )

    async def _put_dec_rate(self, params: Params) -> None:
        value = params.number("DeclinationRate")
        mount = self.session.mount
        await self.session.call(
            mount.set_tracking_rates(mount.tracking_rates.ra_arcsec_per_s, value)
        )

    async def _put_tracking_rate(self, params: Params) -> None:
        value = params.integer("TrackingRate", 0, 3)
        rate = DriveRate(value)
        mount = self.session.mount
        if rate not in supported_drive_rates(mount):
            raise AlpacaError(
                ErrorNumber.INVALID_VALUE, f"tracking rate {rate.name.lower()} is not supported"
            )
        self._drive_rate = rate
        rates = mount.tracking_rates
        if rate is not DriveRate.SIDEREAL and rates.ra_arcsec_per_s != 0.0:
            # RightAscensionRate is an offset from sidereal: it does not ride on another rate.
            await self.session.call(mount.set_tracking_rates(0.0, rates.dec_arcsec_per_s))
        mode = mode_for(mount, rate)
        if mode is not None and mount.state.tracking is not TrackingMode.OFF:
            await self.session.call(mount.set_tracking(mode))
