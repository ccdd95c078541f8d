"""Open a link from the string a user types: a device path, ``COM3``, or a URL."""

from __future__ import annotations

import re
from urllib.parse import urlsplit

from scopelink.links.base import DEFAULT_BAUDRATE, Link, LinkSpecError
from scopelink.links.pacing import paced
from scopelink.links.serial import open_serial
from scopelink.links.tcp import open_tcp

_EXAMPLES = (
    "/dev/ttyUSB0, COM3, tcp://HOST:PORT, socket://HOST:PORT, rfc2217://HOST:PORT or loop://"
)
_SERIAL_SCHEMES_WITH_ADDRESS = frozenset({"socket", "rfc2217"})
_OTHER_SERIAL_SCHEMES = frozenset({"loop", "spy", "alt", "hwgrep", "cp2110"})
# Links whose bytes cross no UART of ours or the remote's: only pacing keeps them at line rate.
_UNTIMED_SCHEMES = frozenset({"tcp", "socket", "loop"})
_HOST_PORT = re.compile(r"^[\w.-]+:\d+$")


async def open_link(
    spec: str, baudrate: int = DEFAULT_BAUDRATE, *, stopbits: int = 1, pace: bool = False
) -> Link:
    """Open the link ``spec`` names; raise LinkSpecError for a malformed one.

    ``baudrate`` and ``stopbits`` set up serial ports (8 data bits, no parity). With ``pace``,
    links that cross no UART (``tcp://``, ``socket://``, ``loop://``) get writes paced to that
    line rate, so the device sees the timing a real port at those settings would give it.
    """
    spec = spec.strip()
    scheme = _scheme_of(spec)
    if scheme == "tcp":
        host, port = _host_and_port(spec)
        link: Link = await open_tcp(host, port)
    elif scheme in _SERIAL_SCHEMES_WITH_ADDRESS:
        _host_and_port(spec)
        link = await open_serial(spec, baudrate, stopbits=stopbits)
    elif scheme in _OTHER_SERIAL_SCHEMES or scheme is None:
        link = await open_serial(spec, baudrate, stopbits=stopbits)
    else:
        raise LinkSpecError(f"unknown link scheme {scheme!r} in {spec!r}; expected {_EXAMPLES}")
    if pace and scheme in _UNTIMED_SCHEMES:
        return paced(link, baudrate, bits_per_byte=1 + 8 + stopbits)
    return link


def _scheme_of(spec: str) -> str | None:
    """The URL scheme, or None for a device path; rejects what cannot be either."""
    if not spec:
        raise LinkSpecError(f"empty link spec; expected {_EXAMPLES}")
    if "://" in spec:
        return spec.split("://", 1)[0].lower()
    if _HOST_PORT.match(spec):
        raise LinkSpecError(f"{spec!r} looks like a network address: did you mean tcp://{spec}?")
    return None


def _host_and_port(spec: str) -> tuple[str, int]:
    parts = urlsplit(spec)
    try:
        port = parts.port
    except ValueError:
        port = None
    if not parts.hostname or port is None:
        scheme = parts.scheme or "tcp"
        raise LinkSpecError(f"{spec!r} needs a host and a port number, like {scheme}://HOST:PORT")
    return parts.hostname, port
