"""What the mount can do and fixed facts: AlignmentMode, EquatorialSystem, the Can* flags, optics.

All come from the mount's :class:`~scopelink.mount.Capabilities` and the configuration, so they
answer without a connection. CanMoveAxis and AxisRates are in ``motion``, TrackingRates in
``tracking``.
"""

from __future__ import annotations

from scopelink.mount import AlignmentMode, TrackingMode
from scopelink.mount.rates import GuideRates
from scopelink.servers.alpaca.telescope.member import Member, MemberGroup, fixed, not_implemented

__all__ = ["CapabilityMembers"]

_ALIGNMENT = {AlignmentMode.ALT_AZ: 0, AlignmentMode.POLAR: 1, AlignmentMode.GERMAN_POLAR: 2}
"""ASCOM ``AlignmentModes``."""


class CapabilityMembers(MemberGroup):
    """The Can* flags and the mount's fixed facts."""

    def members(self) -> dict[str, Member]:
        caps = self.session.mount.capabilities
        ni = not_implemented
        return {
            "alignmentmode": fixed(_ALIGNMENT[caps.alignment_mode]),
            "equatorialsystem": fixed(int(self.session.config.equatorial_system)),
            "canfindhome": fixed(False),
            "canpark": fixed(caps.can_park),
            "canunpark": fixed(caps.can_park),
            "cansetpark": fixed(caps.can_set_park),
            "canpulseguide": fixed(caps.can_pulse_guide),
            "cansetdeclinationrate": fixed(caps.max_tracking_offset_arcsec_s > 0.0),
            "cansetrightascensionrate": fixed(caps.max_tracking_offset_arcsec_s > 0.0),
            "cansetguiderates": fixed(isinstance(self.session.mount, GuideRates)),
            "cansetpierside": fixed(False),
            "cansettracking": fixed(len(caps.tracking_modes - {TrackingMode.OFF}) > 0),
            "canslew": fixed(caps.can_goto),
            "canslewasync": fixed(caps.can_goto),
            "canslewaltaz": fixed(caps.can_goto_altaz),
            "canslewaltazasync": fixed(caps.can_goto_altaz),
            "cansync": fixed(caps.can_sync),
            "cansyncaltaz": fixed(caps.can_sync),
            "aperturearea": Member(get=ni("ApertureArea")),
            "aperturediameter": Member(get=ni("ApertureDiameter")),
            "focallength": Member(get=ni("FocalLength")),
        }
