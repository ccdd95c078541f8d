"""What both drivers do alike: open their link, count its traffic, cut a read short for a stop,
reconnect, and turn a J2000 reading into what the Mount API reports.

- :data:`LinkFactory` and :func:`link_factory`: a link spec (``/dev/ttyUSB0``,
  ``tcp://host:port``, a pty path) or a coroutine function becomes the one way a driver opens,
  and reopens, its link;
- :class:`LinkStatistics`: the counters every driver keeps about its line (health displays,
  benchmarks, tests);
- :class:`PendingRead`: the reply being waited for, which a stop may cut short;
- :class:`Reconnection`: one reconnection at a time, for a poll and a command that both find the
  link lost;
- :class:`Pointing`: one J2000 reading and, computed once on demand, alt/az and RA/Dec of date.

The turn-taking on the wire (user commands before background polls) is
:class:`scopelink.mount.scheduling.WireScheduler`, one per driver: the Mount layer defines it.

See the "Drivers" section of ``docs/architecture.md``.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from datetime import datetime

from scopelink.astro import Site, j2000_to_apparent, j2000_to_observed
from scopelink.links import Link, open_link

__all__ = [
    "LinkFactory",
    "LinkStatistics",
    "PendingRead",
    "Pointing",
    "Reconnection",
    "link_factory",
]

LinkFactory = Callable[[], Awaitable[Link]]
"""Opens the link to the device (called again to reconnect after the link dropped)."""


def link_factory(
    link: str | LinkFactory,
    *,
    name: str | None,
    unnamed: str,
    baudrate: int = 9600,
    stopbits: int = 1,
    pace: bool = False,
) -> tuple[LinkFactory, str]:
    """The factory that opens ``link`` and the name errors give it.

    A spec is opened with :func:`scopelink.links.open_link` and these serial settings; a factory
    is used as it is (``unnamed`` names it unless ``name`` does).
    """
    if not isinstance(link, str):
        return link, name or unnamed
    spec = link

    async def open_spec() -> Link:
        return await open_link(spec, baudrate, stopbits=stopbits, pace=pace)

    return open_spec, name or spec


@dataclass(slots=True)
class LinkStatistics:
    """Counters of one driver's line (for health displays, benchmarks and tests).

    Both drivers count ``exchanges`` … ``interrupted``; ``commands_sent`` (since the link
    opened: the Sky Tracker's ``S`` rule counts them), ``stray_bytes`` and ``bus_refusals`` are
    the Sky Tracker's own.
    """

    exchanges: int = 0
    bytes_sent: int = 0
    bytes_received: int = 0
    failures: int = 0
    resyncs: int = 0
    reconnects: int = 0
    discarded_bytes: int = 0
    stops_at_once: int = 0
    """Stops written without waiting for their turn (see each driver's ``stop_at_once``)."""
    interrupted: int = 0
    """Exchanges cut short by a stop."""
    commands_sent: int = 0
    stray_bytes: int = 0
    bus_refusals: int = 0


@dataclass(slots=True)
class PendingRead:
    """A reply being waited for: its deadline, and whether a stop cut it short (both drivers'
    ``stop_at_once`` interrupt the read in progress rather than wait for it)."""

    deadline: asyncio.Timeout
    interrupted: bool = False

    def interrupt(self) -> None:
        self.interrupted = True
        self.deadline.reschedule(asyncio.get_running_loop().time())


class Reconnection:
    """One reconnection at a time: a poll and a command may both find the link lost, and the
    second must not open it again once the first has."""

    def __init__(self) -> None:
        self._lock = asyncio.Lock()

    async def run_if(
        self, needed: Callable[[], bool], reconnect: Callable[[], Awaitable[None]]
    ) -> bool:
        """Await ``reconnect()`` if ``needed()`` still holds once it is our turn; True if it ran."""
        if not needed():
            return False
        async with self._lock:
            if not needed():
                return False
            await reconnect()
            return True


class Pointing:
    """One J2000 reading (RA hours, Dec degrees, as the device said it at ``read_at``) and what
    the PC derives from it for ``site``: alt/az (observed, refracted) and RA/Dec of date,
    computed once, on demand (:meth:`compute` may run while the line waits for a reply)."""

    __slots__ = ("_derived", "dec_j2000_deg", "ra_j2000_hours", "read_at", "received_s", "site")

    def __init__(
        self,
        ra_j2000_hours: float,
        dec_j2000_deg: float,
        read_at: datetime,
        site: Site,
        received_s: float | None = None,
    ) -> None:
        self.ra_j2000_hours = ra_j2000_hours
        self.dec_j2000_deg = dec_j2000_deg
        self.read_at = read_at
        self.site = site
        self.received_s = time.monotonic() if received_s is None else received_s
        """When the reply arrived (:func:`time.monotonic`): the reading's age."""
        self._derived: tuple[float, float, float, float] | None = None

    def at_site(self, site: Site) -> Pointing:
        """The same reading seen from ``site`` (the device keeps no site of its own)."""
        return Pointing(
            self.ra_j2000_hours, self.dec_j2000_deg, self.read_at, site, self.received_s
        )

    def compute(self) -> tuple[float, float, float, float]:
        """(alt°, az°, RA of date h, Dec of date°), computed on the first call."""
        if self._derived is None:
            ra, dec = self.ra_j2000_hours, self.dec_j2000_deg
            alt, az = j2000_to_observed(ra, dec, self.read_at, self.site)
            ra_of_date, dec_of_date = j2000_to_apparent(ra, dec, self.read_at)
            self._derived = (alt, az, ra_of_date, dec_of_date)
        return self._derived

    @property
    def alt_deg(self) -> float:
        return self.compute()[0]

    @property
    def az_deg(self) -> float:
        return self.compute()[1]

    @property
    def ra_of_date_hours(self) -> float:
        return self.compute()[2]

    @property
    def dec_of_date_deg(self) -> float:
        return self.compute()[3]
