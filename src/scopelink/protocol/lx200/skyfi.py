"""SkySafari's "Auto-Detect SkyFi": one UDP datagram to port 4031 and the unit's answer.

SkySafari asks ``skyfi?`` (or ``skyfi:NAME?`` with the SkyFi name set in its settings); a
SkyFi unit answers with the same text, ``?`` turned into ``@``, followed by its IPv4 address in
dotted form, e.g. ``skyfi:scope@192.168.0.20``. SkySafari then opens TCP port 4030 there.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

__all__ = ["SKYFI_PORT", "SkyFiQuery", "parse_skyfi_query", "skyfi_reply"]

SKYFI_PORT: Final = 4031
SKYFI_TCP_PORT: Final = 4030
"""Where SkySafari connects once it knows the address."""

_PREFIX = b"skyfi"
_MAX_DATAGRAM = 256


@dataclass(frozen=True, slots=True)
class SkyFiQuery:
    """A discovery request; ``name`` is None when SkySafari asked for any unit."""

    text: bytes
    name: str | None

    def matches(self, our_name: str | None) -> bool:
        """Whether a unit called ``our_name`` (None: answer every name) should answer."""
        if self.name is None or our_name is None:
            return True
        return self.name.strip().casefold() == our_name.strip().casefold()


def parse_skyfi_query(datagram: bytes) -> SkyFiQuery | None:
    """The query in ``datagram``, or None if it is not one (including our own replies)."""
    if len(datagram) > _MAX_DATAGRAM or not datagram.endswith(b"?"):
        return None
    if datagram[: len(_PREFIX)].lower() != _PREFIX:
        return None
    body = datagram[len(_PREFIX) : -1]
    if not body:
        return SkyFiQuery(datagram, None)
    if body[:1] != b":":
        return None
    return SkyFiQuery(datagram, body[1:].decode("latin-1"))


def skyfi_reply(query: SkyFiQuery, ipv4_address: str) -> bytes:
    """The unit's answer: the query with ``@`` for ``?``, then ``ipv4_address``."""
    parts = ipv4_address.split(".")
    if len(parts) != 4 or not all(p.isdigit() and int(p) < 256 for p in parts):
        raise ValueError(f"{ipv4_address!r} is not a dotted IPv4 address")
    return query.text[:-1] + b"@" + ipv4_address.encode("ascii")
