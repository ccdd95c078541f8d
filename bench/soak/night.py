"""What the night records, for the report and the checks."""

from __future__ import annotations

import asyncio
import math
import re
from collections import Counter
from collections.abc import Awaitable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import TypeVar

from bench.soak.config import POSITION_READS

T = TypeVar("T")


@dataclass
class Requests:
    """Requests of one protocol: how many, how many errors answered, the slowest, the unanswered."""

    count: int = 0
    errors: int = 0
    slowest_s: float = 0.0
    slowest: str = ""
    """Which request was the slowest, and when."""
    late: list[str] = field(default_factory=list)


@dataclass
class Night:
    """Everything the night records, for the report and the checks."""

    started: float
    """When the clients started, on this process's loop clock."""
    started_wall: datetime = field(default_factory=lambda: datetime.now(UTC))
    """The same moment on the wall clock, which the other processes stamp their events with."""
    requests: dict[str, Requests] = field(default_factory=dict)
    error_texts: Counter[str] = field(default_factory=Counter)
    fault_stamps: list[tuple[datetime, str]] = field(default_factory=list)
    """When the emulator says each fault fired (its log's wall clock), and its kind."""
    wire_commands: int = 0
    serve_log: list[str] = field(default_factory=list)
    reading_advances: list[float] = field(default_factory=list)
    """The read_at of every new reading the dashboards saw (night's clock, see :meth:`at`)."""
    slewing_samples: list[tuple[float, bool]] = field(default_factory=list)
    poll_failed_samples: list[tuple[float, bool]] = field(default_factory=list)
    """(time, whether the state names a failed poll among its problems), every update."""
    motion_commands: list[tuple[float, str]] = field(default_factory=list)
    """(time, what) of every command that moves the mount or stops it."""
    slews: int = 0
    slew_times: list[float] = field(default_factory=list)
    stuck: list[str] = field(default_factory=list)
    broken: list[str] = field(default_factory=list)
    fault_switches: list[tuple[float, str]] = field(default_factory=list)
    """What the bench told the emulator, and when."""
    faults_cleared_at: float = math.inf
    """Client connections refused or broken by the server side."""
    stream_gaps: list[float] = field(default_factory=list)
    withheld: list[tuple[float, str]] = field(default_factory=list)
    """(time, what) of position reads not answered within their bound (see POSITION_READS)."""
    memory: list[tuple[float, int, int]] = field(default_factory=list)
    """(time, RSS KiB, fds) of the serve process, every second."""
    last_problems: list[str] = field(default_factory=list)
    reconnects: Counter[str] = field(default_factory=Counter)
    first_page_s: float = math.nan
    """serve's first dashboard page, before the night: seconds to its hello (cold)."""
    guard_stops: list[float] = field(default_factory=list)
    """When serve's horizon guard stopped the mount."""
    meridian_stops: list[float] = field(default_factory=list)
    """When serve's meridian watch stopped tracking (judged on serve's clock, not the device's
    sky: see :mod:`bench.soak.device_sky`)."""
    device_meridian: tuple[int, float, str] = (0, -math.inf, "not asked")
    """The emulated tube in its own sky: (samples, worst degrees past its meridian limit, where)."""
    final_landing: tuple[float | None, float] = (None, math.inf)
    """The last slew's duration (None: stuck) and its distance from the target in degrees."""

    def now(self) -> float:
        return asyncio.get_running_loop().time() - self.started

    def at(self, moment: datetime) -> float:
        """A wall-clock moment (a reading's read_at, a log line's stamp) on the night's clock:
        unlike arrival times here, it does not depend on this process being prompt."""
        return (moment - self.started_wall).total_seconds()

    def moved(self, what: str) -> None:
        self.motion_commands.append((self.now(), what))

    def of(self, protocol: str) -> Requests:
        return self.requests.setdefault(protocol, Requests())

    async def timed(self, protocol: str, what: str, bound_s: float, work: Awaitable[T]) -> T:
        """Run one request; count it; a request not answered within ``bound_s`` is recorded and
        raises TimeoutError."""
        record = self.of(protocol)
        record.count += 1
        start = self.now()
        try:
            async with asyncio.timeout(bound_s):
                return await work
        except TimeoutError:
            if what in POSITION_READS:
                self.withheld.append((start, f"{protocol} {what} at {start:.1f} s"))
            else:
                record.late.append(f"{what} at {start:.1f} s: no answer within {bound_s:g} s")
            raise
        finally:
            took = self.now() - start
            if took > record.slowest_s:
                record.slowest_s, record.slowest = took, f"{what} at {start:.1f} s"

    def answered_error(self, protocol: str, text: str) -> None:
        self.of(protocol).errors += 1
        self.error_texts[f"{protocol}: {_generic(text)}"] += 1

    @property
    def faults(self) -> list[tuple[float, str]]:
        """(time on the night's clock, kind) of every fault, in order."""
        return [(self.at(stamp), kind) for stamp, kind in self.fault_stamps]


def _generic(text: str) -> str:
    """An error text with its numbers removed, so that like errors count together."""
    return re.sub(r"[-+]?\d[\d.:°'\"]*", "N", text)[:110]
