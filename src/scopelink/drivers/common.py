"""What both drivers do alike: open their link, count its traffic, cut a read short for a stop,
reconnect, and turn a J2000 reading into what the Mount API reports.

- :data:`LinkFactory` and :func:`link_factory`: a link spec (``/dev/ttyUSB0``,
  ``tcp://host:port``, a pty path) or a coroutine function becomes the one way a driver opens,
  and reopens, its link;
- :class:`LinkStatistics`: the counters every driver keeps about its line (health displays,
  benchmarks, tests);
- :class:`ReplyDeadline`: bounds the reply being waited for, which a stop may cut short (one
  timer for a wire's many exchanges: the per-command CPU budget of issue #14);
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
from scopelink.links import DEFAULT_BAUDRATE, Link, open_link
from scopelink.links.prompt import running_task

__all__ = [
    "LinkFactory",
    "LinkStatistics",
    "Pointing",
    "Reconnection",
    "ReplyDeadline",
    "link_factory",
]

LinkFactory = Callable[[], Awaitable[Link]]
"""Opens the link to the device (called again to reconnect after the link dropped)."""


def link_factory(
    link: str | LinkFactory,
    *,
    name: str | None,
    unnamed: str,
    baudrate: int = DEFAULT_BAUDRATE,
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


class ReplyDeadline:
    """Bounds one wire's reads, one at a time: ``with deadline.start(seconds): await ...`` raises
    ``TimeoutError`` out of the block once ``seconds`` have passed, or once :meth:`interrupt`
    (a stop) cut the read short; :attr:`interrupted` tells which.

    It does what ``asyncio.timeout`` does (cancel the waiting task, turn that cancellation into
    ``TimeoutError``, leave a cancellation from elsewhere alone) at a fraction of the CPU: one
    reusable object per wire and one timer handle for many exchanges. The handle is armed for
    the earliest deadline not yet covered; when it fires and the read in progress is not yet
    due (a later exchange moved the deadline on), it re-arms for that read's deadline. A wire
    busy with exchanges that each take less than the timeout therefore handles one timer event
    per timeout period, not one per exchange (issue #14: CPU per command).
    """

    __slots__ = (
        "_cancelling",
        "_expired",
        "_handle",
        "_handle_at",
        "_loop",
        "_task",
        "_when",
        "interrupted",
        "since",
    )

    def __init__(self) -> None:
        self._loop: asyncio.AbstractEventLoop | None = None
        self._task: asyncio.Task[object] | None = None
        """The task reading now (None between reads)."""
        self._cancelling = 0
        self._when: float | None = None
        """Loop time at which the read in progress times out (None: only a stop ends it)."""
        self._handle: asyncio.TimerHandle | None = None
        self._handle_at = float("inf")
        self._expired = False
        self.interrupted = False
        """The last read was cut short by :meth:`interrupt` (not by its timeout)."""
        self.since = 0.0
        """Loop time at which the read in progress (or the last one) started."""

    @property
    def active(self) -> bool:
        """Whether a read is in progress (inside the ``with`` block)."""
        return self._task is not None

    @property
    def loop(self) -> asyncio.AbstractEventLoop:
        """The running event loop (looked up once: each lookup costs a system call)."""
        loop = self._loop
        if loop is None or loop.is_closed():
            loop = self._loop = asyncio.get_running_loop()
            self._handle, self._handle_at = None, float("inf")
        return loop

    def start(self, seconds: float | None, now: float | None = None) -> ReplyDeadline:
        """Begin a read that times out after ``seconds`` (None: never) from ``now`` (loop time;
        default: the clock now, looked up); use as ``with``. One read at a time."""
        # The task is looked up on the loop used last (a C look-up: this runs on every
        # exchange, issue #14); none there means a first read or a new loop: look both up.
        loop = self._loop
        if loop is None or (task := running_task(loop)) is None:
            running = asyncio.get_running_loop()
            if running is not loop:
                self._loop = running
                self._handle, self._handle_at = None, float("inf")
            loop = running
            task = running_task(loop)
            assert task is not None, "a read runs in a task"
        if now is None:
            now = loop.time()
        self._task, self._cancelling = task, task.cancelling()
        self.interrupted = False  # (and _expired, reset by __exit__)
        self.since = now
        if seconds is None:
            self._when = None
        else:
            when = self._when = now + seconds
            if self._handle_at > when:
                self._arm(when)
        return self

    def reschedule(self, when: float) -> None:
        """Move the read's deadline to loop time ``when``."""
        self._when = when
        if self._task is not None and self._handle_at > when:
            self._arm(when)

    def interrupt(self) -> None:
        """Cut the read in progress short (a stop goes first); it leaves with TimeoutError."""
        if self._task is None or self._expired or self._loop is None:
            return
        self.interrupted = True
        # From the loop, as asyncio.timeout's reschedule does: a read that completes without
        # waiting (its bytes were there) is left alone rather than cancelled after it ended.
        self._loop.call_soon(self._expire_interrupted)

    def close(self) -> None:
        """Drop the timer (the wire is closing) unless a read still needs it; a later read arms
        a new one."""
        if self._task is not None:
            return  # the read in progress keeps its deadline (its link's close ends it anyway)
        if self._handle is not None:
            self._handle.cancel()
        self._handle, self._handle_at = None, float("inf")

    def __enter__(self) -> ReplyDeadline:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: object,
    ) -> None:
        task, self._task = self._task, None
        if self._expired:
            self._expired = False  # reset here, not in start(): it is rarely set
            # Our cancellation becomes TimeoutError, unless another came too: that one
            # propagates.
            if (
                task is not None
                and task.uncancel() <= self._cancelling
                and exc_type is asyncio.CancelledError
            ):
                raise TimeoutError from exc

    def _arm(self, when: float) -> None:
        loop = self._loop
        assert loop is not None
        if self._handle is not None:
            self._handle.cancel()
        self._handle = loop.call_at(when, self._on_timer)
        self._handle_at = when

    def _on_timer(self) -> None:
        self._handle, self._handle_at = None, float("inf")
        when = self._when
        if self._task is None or when is None or self._loop is None:
            return  # no read in progress: the next one arms a timer of its own
        if self._loop.time() >= when:
            self._expire()
        else:
            self._arm(when)

    def _expire_interrupted(self) -> None:
        if self.interrupted:  # else the interrupted read ended and another started meanwhile
            self._expire()

    def _expire(self) -> None:
        task = self._task
        if task is None or self._expired:
            return  # that read ended meanwhile
        self._expired = True
        task.cancel()


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
