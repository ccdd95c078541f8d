"""What an emulated SynScan hand control says about itself, and which firmware quirks it has."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from scopelink.protocol.synscan import Version, VersionDialect

__all__ = ["DEFAULT_FIRMWARE", "MAX_LATENCY_SECONDS", "Quirks", "SynScanConfig"]

DEFAULT_FIRMWARE = Version(4, 39, 5)
"""04.39.05: a V4 release INDI accepts without its "firmware too old" warning (it wants 4.38+)."""

MAX_LATENCY_SECONDS = 5.0
"""The spec's worst case for a reply; clients must wait this long."""

DEFAULT_SYNC_LIMIT_DEG = 7.0
"""Real hand controls acknowledge, then ignore, a sync more than about 6-7° from their position."""


@dataclass(frozen=True, slots=True)
class Quirks:
    """Behaviour of real controllers that clients depend on or work around (``specs/NOTES.md``).

    The defaults are those of a current V4 hand control.
    """

    sync_limit_deg: float | None = DEFAULT_SYNC_LIMIT_DEG
    """A sync further than this from the current position is acknowledged and ignored; None obeys
    every sync."""
    sticky_altaz_goto: bool = False
    """After an Alt-Az (``B``/``b``) goto, ``L`` answers '1' until ``M`` or the next goto."""
    resume_after_cancel: bool = False
    """``M`` stops a goto, but axes moving at a fixed or variable rate start again (firmware up to
    3.36); only rate 0 stops them for good."""
    failed_passthrough: bool = True
    """A passthrough no motor controller answers gets the requested bytes, one extra byte and
    ``#``; False answers zero bytes and ``#`` as if it succeeded."""
    model_swapped: bool = False
    """``m`` answers ``#`` first, then the model code (firmware 3.39)."""

    def __post_init__(self) -> None:
        if self.sync_limit_deg is not None and not 0.0 < self.sync_limit_deg <= 180.0:
            raise ValueError(f"sync limit {self.sync_limit_deg}° must lie in (0, 180]")


@dataclass(frozen=True, slots=True)
class SynScanConfig:
    """Identity and timing of an emulated hand control.

    ``model`` is the ``m`` code (0 EQ6 ... 165 AZ-GTi). ``firmware`` is the ``V`` reply; give a
    ``Version`` in the old 3-byte binary dialect to emulate firmware that answers that way.
    ``aligned`` is the hand control's own alignment state (the motor controllers know none): ``J``
    answers it, RA/Dec gotos and syncs are ignored without it, and Alt-Az positions are relative to
    where the mount was at power-on. ``latency_s`` delays every reply (the spec allows up to 5 s).
    ``motor_version`` is what ``P`` device version answers for both motor controllers.
    """

    model: int = 0
    firmware: Version = DEFAULT_FIRMWARE
    aligned: bool = True
    latency_s: float = 0.0
    motor_version: tuple[int, int] = (3, 39)
    quirks: Quirks = field(default_factory=Quirks)

    def __post_init__(self) -> None:
        if not 0 <= self.model <= 0xFF:
            raise ValueError(f"model code {self.model} must be a byte (0-255)")
        if self.model == 0x23 and self.quirks.model_swapped:
            raise ValueError("model code 35 ('#') cannot be sent in the swapped dialect")
        if self.firmware.dialect is VersionDialect.NEXSTAR_BINARY:
            raise ValueError("a SynScan hand control does not answer V in the NexStar dialect")
        if not (math.isfinite(self.latency_s) and 0.0 <= self.latency_s <= MAX_LATENCY_SECONDS):
            raise ValueError(
                f"latency {self.latency_s} s must lie in [0, {MAX_LATENCY_SECONDS:g}] (the spec's"
                " worst case; use a delay fault to go beyond it)"
            )
        for part in self.motor_version:
            if not 0 <= part <= 0xFF:
                raise ValueError(f"motor controller version {self.motor_version} must be bytes")

    @property
    def equatorial(self) -> bool:
        """Whether the model code is an equatorial mount (as clients decide: codes below 128)."""
        return self.model < 128
