"""Which ``Host`` names a server answers to, and which client networks are "local".

A web page on ``http://evil.example:PORT/`` whose name the attacker re-points at 127.0.0.1 (DNS
rebinding) makes the victim's browser send same-origin requests to our servers, with
``Host: evil.example:PORT``. The only thing that tells such a request from a real one is its
``Host``: :class:`HostAllowList` admits the names and addresses this machine really has (the
bound address, ``localhost``, loopback addresses, and when bound beyond loopback the machine's
names and interface addresses) plus the names the user lists (``servers.allowed_hosts``); HTTP
servers answer any other ``Host`` with ``421 Misdirected Request``.
"""

from __future__ import annotations

import ipaddress
import logging
import socket
from collections.abc import Iterable

import psutil

from scopelink.servers.access import IPNetwork

__all__ = [
    "WARNED_MISDIRECTED",
    "HostAllowList",
    "bound_beyond_loopback",
    "local_networks",
    "machine_addresses",
]

logger = logging.getLogger(__name__)

_LOOPBACK_NAMES = frozenset({"localhost", "localhost.localdomain", "ip6-localhost"})

WARNED_MISDIRECTED = 10
"""Requests for a foreign Host (answered 421) logged as warnings by each server; later ones are
debug messages: a page trying DNS rebinding retries, and a warning each time would flood the log."""


def bound_beyond_loopback(host: str) -> bool:
    """Whether listening on ``host`` is reachable from other machines (names count as such,
    except ``localhost``)."""
    text = host.strip("[]")
    try:
        return not ipaddress.ip_address(text.split("%", 1)[0]).is_loopback
    except ValueError:
        return text.lower() not in _LOOPBACK_NAMES


def _interfaces() -> list[tuple[str, str | None]]:
    """(address, netmask) of every IPv4 and IPv6 address of this machine's interfaces."""
    found: list[tuple[str, str | None]] = []
    try:
        table = psutil.net_if_addrs()
    except OSError as error:  # no /proc, a sandbox: only what we are told
        logger.warning("cannot list this machine's network interfaces: %s", error)
        return found
    for addresses in table.values():
        for entry in addresses:
            if entry.family in (socket.AF_INET, socket.AF_INET6):
                found.append((entry.address.split("%", 1)[0], entry.netmask))
    return found


def machine_addresses() -> frozenset[str]:
    """Every address of this machine's interfaces, in canonical text form."""
    return frozenset(str(ipaddress.ip_address(address)) for address, _ in _interfaces())


def local_networks() -> tuple[IPNetwork, ...]:
    """The subnets this machine's interfaces are on (what "the local network" admits)."""
    networks: list[IPNetwork] = []
    for address, netmask in _interfaces():
        if netmask is None:
            continue
        try:
            if ":" in address:
                prefix = ipaddress.IPv6Network(f"::/{netmask}").prefixlen
                network: IPNetwork = ipaddress.IPv6Network(f"{address}/{prefix}", strict=False)
            else:
                network = ipaddress.IPv4Network(f"{address}/{netmask}", strict=False)
        except ValueError:
            continue
        if network not in networks:
            networks.append(network)
    return tuple(networks)


def _normal(name: str) -> str:
    """A host name or address as compared: lower case, no trailing dot, addresses canonical."""
    text = name.strip().lower().rstrip(".")
    if text.startswith("[") and text.endswith("]"):
        text = text[1:-1]
    try:
        return str(ipaddress.ip_address(text))
    except ValueError:
        return text


def split_host_header(value: str) -> str:
    """The host part of a ``Host`` header value or URL authority (``name:port``, ``[v6]:port``)."""
    value = value.strip()
    if value.startswith("["):
        end = value.find("]")
        return value[: end + 1] if end > 0 else value
    if value.count(":") == 1:
        return value.split(":", 1)[0]
    return value


class HostAllowList:
    """The ``Host`` names a server on ``bind_host`` answers to.

    Always: the bind address itself, ``localhost`` and every loopback address. When bound beyond
    loopback (``0.0.0.0``, ``::``, a LAN address or a name): also this machine's host name, its
    fully qualified name, ``NAME.local`` (mDNS) and every address of its interfaces. ``extra``
    adds names or addresses (``servers.allowed_hosts``: a DNS name the LAN gives the machine, a
    reverse proxy's name).
    """

    def __init__(self, bind_host: str, extra: Iterable[str] = ()) -> None:
        names = set(_LOOPBACK_NAMES)
        names.add(_normal(bind_host))
        names.update(_normal(item) for item in extra if item.strip())
        self.beyond_loopback = bound_beyond_loopback(bind_host)
        if self.beyond_loopback:
            hostname = socket.gethostname()
            names.update(_normal(n) for n in (hostname, f"{hostname}.local", socket.getfqdn()))
            names.update(machine_addresses())
        # A wildcard bind address stays: it is what serve prints, and a browser on this machine
        # opening it sends it as Host; no page of another site can have it as its own name.
        names.discard("")
        self.names = frozenset(names)

    def allows(self, host_header: str | None) -> bool:
        """Whether a request with this ``Host`` header value is for us. No header at all (an
        HTTP/1.0 client) passes: every browser sends one, so it cannot be a rebinding attack."""
        if host_header is None:
            return True
        name = _normal(split_host_header(host_header))
        if name in self.names:
            return True
        try:
            return ipaddress.ip_address(name).is_loopback
        except ValueError:
            return False

    def allows_origin(self, origin_authority: str) -> bool:
        """Whether a page served from ``origin_authority`` (``host:port``) is one of ours."""
        return self.allows(origin_authority)

    def describe(self) -> str:
        return ", ".join(sorted(self.names))
