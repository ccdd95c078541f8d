"""What the LX200 server says about itself and how it answers where clients disagree."""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

from scopelink import __version__
from scopelink.astro import SIDEREAL_RATE_DEG_S
from scopelink.protocol.lx200 import SlewRate

__all__ = ["DEFAULT_RATES_SIDEREAL", "LX200Config", "SyncReply"]

DEFAULT_RATES_SIDEREAL = {
    SlewRate.GUIDE: 0.5,
    SlewRate.CENTER: 8.0,
    SlewRate.FIND: 64.0,
    SlewRate.SLEW: math.inf,
}
"""``:RG# :RC# :RM# :RS#`` in multiples of the sidereal rate; ``inf`` is the mount's maximum."""


class SyncReply(enum.Enum):
    """How ``:CM#`` is answered, since clients read it differently.

    - ``STATUS``: ``0#`` (refused: ``1<reason>#``). Stellarium reads the first byte as a status
      (``0`` ok, ``1``/``2`` + text + ``#`` failed) and skips the leftover ``#``; INDI and
      SkySafari read up to ``#`` and take any text as success. The default: it satisfies all.
    - ``MEADE``: the handset's two 16-character display lines and ``#``
      (``Coordinates     matched.        #``), as Autostar-family handsets answer. Stellarium
      reports such a reply as "sync returns something weird".
    """

    STATUS = "status"
    MEADE = "meade"


@dataclass(frozen=True, slots=True)
class LX200Config:
    """Identity and choices of the emulated handset."""

    product: str = "scopelink"
    """``:GVP#``."""
    firmware: str = __version__
    """``:GVN#``."""
    firmware_date: str = "Nov 22 2026"
    """``:GVD#`` (Meade writes ``mmm dd yyyy``)."""
    firmware_time: str = "00:00:00"
    """``:GVT#``."""
    site_name: str = "scopelink"
    """``:GM# :GN# :GO# :GP#`` (the handset's four site names; we keep one site)."""
    sync_reply: SyncReply = SyncReply.STATUS
    high_precision: bool = True
    """Precision a new connection starts in (``:U#`` toggles it per connection)."""
    utc_offset_hours: float = 0.0
    """Meade's offset at start: hours to *add to local time* to get UTC (``:SG#`` changes it)."""
    rates_sidereal: dict[SlewRate, float] = field(
        default_factory=lambda: dict(DEFAULT_RATES_SIDEREAL)
    )

    def __post_init__(self) -> None:
        if not -14.0 <= self.utc_offset_hours <= 14.0:
            raise ValueError(f"UTC offset {self.utc_offset_hours} h must lie in [-14, 14]")
        if set(self.rates_sidereal) != set(SlewRate):
            raise ValueError("rates_sidereal must give a rate for each of G, C, M and S")
        for rate, multiple in self.rates_sidereal.items():
            if not multiple > 0.0:
                raise ValueError(f"rate {rate.name} must be positive, not {multiple}")
        for text in (
            self.product,
            self.site_name,
            self.firmware,
            self.firmware_date,
            self.firmware_time,
        ):
            if "#" in text or not text.isascii():
                raise ValueError(f"{text!r} must be ASCII without '#'")

    def rate_deg_s(self, rate: SlewRate, max_rate_deg_s: float) -> float:
        """The axis rate for ``rate``, capped at the mount's maximum."""
        return min(self.rates_sidereal[rate] * SIDEREAL_RATE_DEG_S, max_rate_deg_s)
