"""Where the mount points and what it is doing: Altitude, RightAscension, Slewing, SideOfPier...

Every read comes from the mount's state cache, never from the wire; the device refuses the ones
whose reading is not current (``device._FRESH_READS``).
"""

from __future__ import annotations

from scopelink.mount import AlignmentMode
from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope.member import Member, MemberGroup, not_implemented

__all__ = ["PositionMembers"]


class PositionMembers(MemberGroup):
    """The position in both frames, the pier side, sidereal time and the state flags."""

    def members(self) -> dict[str, Member]:
        session = self.session
        mount = session.mount
        return {
            "altitude": Member(get=lambda _: session.known(mount.state.alt_deg, "altitude")),
            "azimuth": Member(get=lambda _: session.known(mount.state.az_deg, "azimuth")),
            "rightascension": Member(get=lambda _: session.radec()[0]),
            "declination": Member(get=lambda _: session.radec()[1]),
            "athome": Member(get=lambda _: False),
            "atpark": Member(get=lambda _: mount.state.parked),
            "slewing": Member(get=lambda _: session.slewing),
            "ispulseguiding": Member(get=lambda _: mount.state.pulse_guiding),
            "sideofpier": Member(get=self._side_of_pier, put=not_implemented("Setting SideOfPier")),
            "destinationsideofpier": Member(get=self._destination_side_of_pier),
            "siderealtime": Member(get=lambda _: session.sidereal_time()),
        }

    def _side_of_pier(self, _: Params) -> int:
        mount = self.session.mount
        if not mount.capabilities.can_report_pier_side:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount does not report pier side")
        return int(mount.state.pier_side)

    def _destination_side_of_pier(self, params: Params) -> int:
        ra = params.number("RightAscension", 0.0, 24.0)
        dec = params.number("Declination", -90.0, 90.0)
        mount = self.session.mount
        if mount.capabilities.alignment_mode is not AlignmentMode.GERMAN_POLAR:
            raise AlpacaError(
                ErrorNumber.NOT_IMPLEMENTED, "only a German equatorial mount has a pier side"
            )
        # The side the goto would take now, the meridian limits included (docs/meridian.md);
        # pierUnknown (-1) where the limits would refuse the goto.
        ra_j2000, dec_j2000 = self.session.to_j2000(ra % 24.0, dec)
        return int(mount.destination_side_of_pier(ra_j2000, dec_j2000))
