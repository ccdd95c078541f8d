"""Stellarium's telescope-control messages (protocol version 1.0) and their wire units.

Every message starts with LENGTH (uint16, the whole message in bytes) and TYPE (uint16), both
little-endian like every integer in the protocol. Only type 0 exists in each direction:

- client -> server, *goto* (20 bytes): TIME int64 (µs since 1970, unused), RA uint32, DEC int32;
- server -> client, *current position* (24 bytes): TIME, RA, DEC, STATUS int32 (0 = ok).

RA counts 2**32 per 24 h; DEC counts 2**30 per 90° (so ±0x40000000 are the poles).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from typing import Final

from scopelink.protocol.base import Message

__all__ = [
    "CURRENT_POSITION_LENGTH",
    "DEC_UNITS_PER_DEGREE",
    "GOTO_LENGTH",
    "HEADER_LENGTH",
    "MESSAGE_TYPE_POSITION",
    "RA_UNITS_PER_HOUR",
    "CurrentPosition",
    "GotoMessage",
    "dec_from_wire",
    "dec_to_wire",
    "ra_from_wire",
    "ra_to_wire",
]

HEADER_LENGTH: Final = 4
GOTO_LENGTH: Final = 20
CURRENT_POSITION_LENGTH: Final = 24
MESSAGE_TYPE_POSITION: Final = 0
"""Type 0: a goto from the client, the current position from the server."""

RA_UNITS_PER_HOUR: Final = 2**32 / 24.0
DEC_UNITS_PER_DEGREE: Final = 2**30 / 90.0

_GOTO = struct.Struct("<HHqIi")
_POSITION = struct.Struct("<HHqIii")


def ra_to_wire(ra_hours: float) -> int:
    """RA in hours -> uint32 (rounded to the nearest unit, 24 h wrapping to 0)."""
    if not math.isfinite(ra_hours):
        raise ValueError(f"right ascension {ra_hours} h is not a number")
    return round(ra_hours % 24.0 * RA_UNITS_PER_HOUR) % 2**32


def ra_from_wire(units: int) -> float:
    """uint32 -> RA in hours [0, 24)."""
    return (units % 2**32) / RA_UNITS_PER_HOUR


def dec_to_wire(dec_deg: float) -> int:
    """Declination in degrees [-90, 90] -> int32."""
    if not (math.isfinite(dec_deg) and -90.0 <= dec_deg <= 90.0):
        raise ValueError(f"declination {dec_deg}° must lie in [-90, +90]")
    return round(dec_deg * DEC_UNITS_PER_DEGREE)


def dec_from_wire(units: int) -> float:
    """int32 -> declination in degrees (values past the poles come out past ±90 as sent)."""
    return units / DEC_UNITS_PER_DEGREE


@dataclass(frozen=True, slots=True)
class GotoMessage(Message):
    """Client -> server: slew to this position (J2000 unless the client is set to JNow).

    Wire units are stored exactly; ``ra_hours`` and ``dec_deg`` give plain units.
    """

    ra_units: int
    dec_units: int
    client_time_us: int = 0

    @classmethod
    def from_degrees(cls, ra_hours: float, dec_deg: float, client_time_us: int = 0) -> GotoMessage:
        return cls(ra_to_wire(ra_hours), dec_to_wire(dec_deg), client_time_us)

    @property
    def ra_hours(self) -> float:
        return ra_from_wire(self.ra_units)

    @property
    def dec_deg(self) -> float:
        return dec_from_wire(self.dec_units)

    def describe(self) -> str:
        return f"goto RA {self.ra_hours:.5f} h, Dec {self.dec_deg:+.5f}°"

    def encode(self) -> bytes:
        return _GOTO.pack(
            GOTO_LENGTH, MESSAGE_TYPE_POSITION, self.client_time_us, self.ra_units, self.dec_units
        )

    @classmethod
    def decode(cls, frame: bytes) -> GotoMessage:
        """A whole 20-byte goto frame (length and type already checked by the parser)."""
        _, _, time_us, ra, dec = _GOTO.unpack(frame)
        return cls(ra, dec, time_us)


@dataclass(frozen=True, slots=True)
class CurrentPosition(Message):
    """Server -> client: where the telescope points now; ``status`` 0 is ok, below 0 an error."""

    ra_units: int
    dec_units: int
    server_time_us: int = 0
    status: int = 0

    @classmethod
    def from_degrees(
        cls, ra_hours: float, dec_deg: float, server_time_us: int = 0, status: int = 0
    ) -> CurrentPosition:
        return cls(ra_to_wire(ra_hours), dec_to_wire(dec_deg), server_time_us, status)

    @property
    def ra_hours(self) -> float:
        return ra_from_wire(self.ra_units)

    @property
    def dec_deg(self) -> float:
        return dec_from_wire(self.dec_units)

    def describe(self) -> str:
        state = "ok" if self.status == 0 else f"error {self.status}"
        return f"at RA {self.ra_hours:.5f} h, Dec {self.dec_deg:+.5f}° ({state})"

    def encode(self) -> bytes:
        return _POSITION.pack(
            CURRENT_POSITION_LENGTH,
            MESSAGE_TYPE_POSITION,
            self.server_time_us,
            self.ra_units,
            self.dec_units,
            self.status,
        )

    @classmethod
    def decode(cls, frame: bytes) -> CurrentPosition:
        """A whole 24-byte position frame."""
        _, _, time_us, ra, dec, status = _POSITION.unpack(frame)
        return cls(ra, dec, time_us, status)
