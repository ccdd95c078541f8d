"""Mount presets and the SynScan hand control's speed table.

Rates are in degrees per second; the sidereal, lunar and solar rates are
:mod:`scopelink.astro.rates`'s.

The SynScan fixed slew rates are the hand control's speed keys. Sky-Watcher's SynScan V3/V4 hand
control manual (section "Slew the mount with the direction keys") lists ten speeds as multiples
of the sidereal rate: 1.0X, 2.0X, 8X, 16X, 32X, 64X, 128X, 400X, 600X and 800X (the last about
3.4°/s). The serial protocol's fixed rates 1-9 "mimic the equivalent hand control rates", so rate
*n* is the hand control's speed *n*: rate 1 = 2X, rate 2 = 8X, ..., rate 9 = 800X. Rates 1 and 2
(0.008°/s and 0.033°/s) are the only ones the protocol lets run on top of equatorial tracking,
which is what makes them usable for guiding.
"""

from __future__ import annotations

from dataclasses import dataclass

from scopelink.astro import SIDEREAL_RATE_DEG_S
from scopelink.mount import AlignmentMode

__all__ = [
    "AZ_GTI",
    "DOB_GOTO",
    "EQ6",
    "HEQ5",
    "PRESETS",
    "SKY_TRACKER",
    "SYNSCAN_FIXED_RATES_DEG_S",
    "SYNSCAN_FIXED_RATE_MULTIPLES",
    "MountModel",
    "synscan_fixed_rate_deg_s",
]


SYNSCAN_FIXED_RATE_MULTIPLES: tuple[float, ...] = (
    2.0,
    8.0,
    16.0,
    32.0,
    64.0,
    128.0,
    400.0,
    600.0,
    800.0,
)
"""SynScan fixed rates 1..9 as multiples of the sidereal rate (index 0 is rate 1)."""

SYNSCAN_FIXED_RATES_DEG_S: tuple[float, ...] = tuple(
    multiple * SIDEREAL_RATE_DEG_S for multiple in SYNSCAN_FIXED_RATE_MULTIPLES
)
"""SynScan fixed rates 1..9 in degrees per second (index 0 is rate 1)."""


def synscan_fixed_rate_deg_s(rate: int) -> float:
    """Degrees per second of SynScan fixed rate ``rate`` (0 stops, 1-9 the hand control keys)."""
    if not 0 <= rate <= len(SYNSCAN_FIXED_RATES_DEG_S):
        raise ValueError(f"SynScan fixed rate {rate} must lie in 0..9")
    return 0.0 if rate == 0 else SYNSCAN_FIXED_RATES_DEG_S[rate - 1]


@dataclass(frozen=True, slots=True)
class MountModel:
    """What a simulated mount is: geometry, speed, acceleration and identity.

    ``acceleration_deg_s2`` is the same on both axes; ``max_rate_deg_s / acceleration_deg_s2``
    is how long a full-speed ramp takes. ``synscan_model_code`` is what the SynScan ``m``
    command answers (``None`` for mounts without a SynScan hand control).
    """

    name: str
    alignment_mode: AlignmentMode
    max_rate_deg_s: float
    acceleration_deg_s2: float
    synscan_model_code: int | None = None
    guide_rate_deg_s: float = 0.5 * SIDEREAL_RATE_DEG_S


_RATE_9 = SYNSCAN_FIXED_RATES_DEG_S[-1]

EQ6 = MountModel("EQ6", AlignmentMode.GERMAN_POLAR, _RATE_9, _RATE_9, synscan_model_code=0)
"""EQ6-class German equatorial: 3.34°/s at rate 9, full-speed ramp in 1 s."""
HEQ5 = MountModel("HEQ5", AlignmentMode.GERMAN_POLAR, _RATE_9, _RATE_9, synscan_model_code=1)
"""HEQ5: same drive electronics and speeds as the EQ6 class."""
AZ_GTI = MountModel("AZ-GTi", AlignmentMode.ALT_AZ, _RATE_9, _RATE_9, synscan_model_code=165)
"""AZ GTi alt-azimuth mount."""
DOB_GOTO = MountModel("Dob GOTO", AlignmentMode.ALT_AZ, _RATE_9, _RATE_9 / 2.0, 144)
"""Sky-Watcher GOTO Dobsonian: heavier tube, full-speed ramp in 2 s."""
SKY_TRACKER = MountModel("Sky Tracker", AlignmentMode.ALT_AZ, 4.0, 2.0)
"""Sky Tracker alt-azimuth drive: 4°/s utility slews, ramped up and down over 2 s."""

PRESETS: dict[str, MountModel] = {
    model.name.lower(): model for model in (EQ6, HEQ5, AZ_GTI, DOB_GOTO, SKY_TRACKER)
}
"""Presets by lower-case name ("eq6", "heq5", "az-gti", "dob goto", "sky tracker")."""
