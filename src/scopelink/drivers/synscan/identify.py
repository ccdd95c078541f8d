"""What a SynScan hand control said about itself, and what the Mount API may offer for it.

The model code of ``m`` decides the geometry (codes below 128 are equatorial, as every client
decides; the dual-mode AZ-EQ5/AZ-EQ6 report themselves as equatorial when set up so), and with
it the tracking modes and whether the pier side (``p``) and guide pulses make sense.
"""

from __future__ import annotations

from dataclasses import dataclass

from scopelink.astro import SIDEREAL_RATE_DEG_S
from scopelink.mount import AlignmentMode, Capabilities, Identity, TrackingMode
from scopelink.protocol.synscan import Model, Tracking, Version, VersionDialect

MAX_SYNSCAN_TRACKING_OFFSET_ARCSEC_S = 3600.0
"""Largest custom rate offset on a SynScan mount (1°/s per axis; the slew command reaches
~4.5°/s, and the guard's budget is made for manual motion at such speeds)."""

__all__ = [
    "MAX_SLEW_RATE_DEG_S",
    "MAX_SYNSCAN_TRACKING_OFFSET_ARCSEC_S",
    "HandControlInfo",
    "capabilities_for",
    "firmware_text",
    "mount_tracking",
    "synscan_tracking",
]

MAX_SLEW_RATE_DEG_S = 800.0 * SIDEREAL_RATE_DEG_S
"""The hand control's top speed (key 9, 800x sidereal, 3.34°/s): the fastest rate offered."""

_TRACKING_CODES: dict[TrackingMode, Tracking] = {
    TrackingMode.OFF: Tracking.OFF,
    TrackingMode.ALT_AZ: Tracking.ALT_AZ,
    TrackingMode.SIDEREAL: Tracking.EQUATORIAL,
    TrackingMode.PEC: Tracking.PEC,
}
_MOUNT_TRACKING: dict[int, TrackingMode] = {code: mode for mode, code in _TRACKING_CODES.items()}


def synscan_tracking(mode: TrackingMode) -> Tracking:
    """The ``T`` code of a tracking mode; lunar, solar and King are the hand control's sidereal
    (the driver's loop adds their offsets: rates.py)."""
    return _TRACKING_CODES.get(mode, Tracking.EQUATORIAL)


def mount_tracking(code: int) -> TrackingMode | None:
    """The tracking mode a ``t`` reply names; None for a code the spec does not define."""
    return _MOUNT_TRACKING.get(code)


def firmware_text(version: Version) -> str:
    """``04.39.05`` for 4.39.5, whichever dialect ``V`` answered in."""
    return f"{version.major:02d}.{version.minor:02d}.{version.patch or 0:02d}"


@dataclass(frozen=True, slots=True)
class HandControlInfo:
    """The answers to the identification queries at connect."""

    version: Version
    model: Model
    motor_versions: tuple[tuple[int, int] | None, tuple[int, int] | None] = (None, None)

    @property
    def equatorial(self) -> bool:
        return self.model.is_equatorial

    @property
    def old_firmware(self) -> bool:
        """Firmware the spec does not cover (below 3.38, or the 4.00-4.37 V4 releases)."""
        numbers = self.version.as_tuple()
        too_old_v3 = numbers < (3, 38, 0)
        early_v4 = (4, 0, 0) <= numbers < (4, 38, 0)
        return too_old_v3 or early_v4 or self.version.dialect is VersionDialect.SYNSCAN_BINARY

    def identity(self, link_name: str) -> Identity:
        return Identity(
            "synscan", self.model.name, firmware=firmware_text(self.version), link=link_name
        )


def capabilities_for(info: HandControlInfo) -> Capabilities:
    """What the Mount API offers for this hand control and model."""
    equatorial = info.equatorial
    sky_tracking = TrackingMode.SIDEREAL if equatorial else TrackingMode.ALT_AZ
    # An alt-az mount offers sidereal too: its alt-az tracking (custom rates are offsets from it).
    modes = {TrackingMode.OFF, sky_tracking, TrackingMode.SIDEREAL}
    if equatorial:
        modes.add(TrackingMode.PEC)
        # Lunar, solar and King: sidereal plus an RA offset, by the PC loop (rates.py).
        modes |= {TrackingMode.LUNAR, TrackingMode.SOLAR, TrackingMode.KING}
    return Capabilities(
        alignment_mode=AlignmentMode.GERMAN_POLAR if equatorial else AlignmentMode.ALT_AZ,
        can_goto=True,
        can_goto_altaz=True,
        can_sync=True,
        can_park=True,
        can_set_park=True,
        # Guide pulses are variable-rate slews timed on the PC; on an alt-az mount north/east
        # are no fixed axis directions, so they are offered on equatorial mounts only.
        can_pulse_guide=equatorial,
        can_move_axis=(True, True),
        max_axis_rate_deg_s=MAX_SLEW_RATE_DEG_S,
        tracking_modes=frozenset(modes),
        can_set_site=True,
        can_set_time=True,
        can_report_pier_side=equatorial,
        # Custom rates: a PC loop of rate slews on the RA/Dec axes (rates.py) or, on an alt-az
        # mount, on the azimuth and altitude axes (altaz_rates.py).
        max_tracking_offset_arcsec_s=MAX_SYNSCAN_TRACKING_OFFSET_ARCSEC_S,
    )
