"""Soak: a simulated night of a SynScan mount behind every server, under client load and faults.

Run ``.venv/bin/python -m bench.soak`` (10 simulated hours at x100: 6 minutes) or
``--hours H --rate X --seed N``; ``--quick`` is the 1-hour x200 run the test suite makes. The stack
is the one a user runs, each part in its own process:

    python -m bench.soak --emulator   the SynScan emulator at --clock-rate X, as 'scopelink
                                      emulate synscan --tcp' runs it, faults switched on stdin
      <- scopelink serve --device synscan:tcp://...  (the process under test)
        <- this process: Alpaca, LX200, Stellarium, SynScan and dashboard WebSocket clients

The emulated sky runs X times faster than real time; the driver, the servers and the clients run
in real time, so a 180 degree slew at the EQ6's 3.4 deg/s lands in about half a real second at
x100. Seeded probabilistic faults of every kind, each fired a fixed number of times, and two
outages (stall, halt) come in the first 70 % of the night; then every fault is cleared and the
rest of the night shows recovery. See ``docs/reliability-soak.md`` for the checks and bounds.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import dataclasses
import itertools
import logging
import math
import os
import random
import re
import signal
import statistics
import struct
import sys
import tempfile
from collections import Counter
from collections.abc import AsyncIterator, Awaitable, Callable, Coroutine
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, TypeVar

import aiohttp

from bench.processes import environment, start_scopelink
from scopelink.astro import Site, observed_to_apparent, observed_to_j2000
from scopelink.links import LinkError, open_tcp, precise_event_loop
from scopelink.protocol.lx200.angles import format_dec, format_ra
from scopelink.protocol.stellarium import GotoMessage
from scopelink.protocol.synscan import (
    NEED_DATA,
    AnyReply,
    GetRaDec,
    Position,
    SynScanClientConnection,
)
from scopelink.servers.faults import Fault, FaultInjector
from scopelink.servers.hosting import SERIAL_9600_8N1
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

ROOT = Path(__file__).resolve().parent.parent
SITE = Site(51.4779, -0.0015)  # serve's and the emulator's default site (Greenwich)
LOWEST_TARGET_ALT_DEG = 25.0
"""Targets are drawn above this altitude: far above the 0 degree horizon even after the emulated
sky (x100) has turned under a tracking-off mount for a few real seconds."""

# --- the bounds every check uses (real seconds) --------------------------------------------------
DRIVER_TIMEOUT_S = 5.0
"""The SynScan driver's reply timeout (the spec's 5 s)."""
READ_BOUND_S = 2.0
"""A read answered from the state cache (Alpaca GETs, LX200 :GR#, SynScan e) never waits on the
wire, so even under faults it must come back within this."""
COMMAND_BOUND_S = 4 * DRIVER_TIMEOUT_S
"""A command that goes to the wire may meet a fault: a timeout, the resynchronising echo (which
may time out too) and one retry: 3 timeouts, plus scheduling: 20 s."""
SLEW_BOUND_S = 30.0
"""From the last motion command to Slewing false. A slew itself lasts under 1 real second at
x100; the rest is for a poll that meets faults (each up to 3 driver timeouts)."""
POLL_GAP_BOUND_S = 4 * DRIVER_TIMEOUT_S
"""Longest time the state cache may go without a new reading while faults fire (plus the
length of an outage when the night has them: the device is silent that long, then the exchange
in flight and its resynchronising echo time out)."""
QUIET_POLL_GAP_BOUND_S = DRIVER_TIMEOUT_S
"""Longest time without a new reading while no fault is in force (after ``QUIET_SETTLE_S``): a
longer gap means an exchange timed out with nothing to blame. Polls come every ~0.1 s; on a
loaded 2-core machine the longest quiet gap measured was 3.6 s (typically 1-1.5 s)."""
QUIET_SETTLE_S = 8.0
"""After a fault, time allowed before the quiet bounds apply: the worst single fault (a reply 6 s
late) costs 6 s, then the resynchronising echo and the retry."""
QUIET_WINDOW_MIN_S = 3.0
"""Shortest stretch without faults (after the settling time) that is judged."""
POSITION_READS = frozenset({"position", ":GR#", ":GD#", ":GA#", ":GZ#", "e"})
"""Reads of the position (Stellarium's stream, LX200, SynScan): not answered while the mount's
reading is older than ``stale_after_s`` (issue #11: no reply, no packet), which a fault that
silences the device causes. Unanswered inside a fault's span (to ``QUIET_SETTLE_S`` after it)
they are counted as withheld; anywhere else they fail the check like any unanswered read."""
STREAM_GAP_BOUND_S = 2.0
"""Stellarium positions come every 0.5 s whatever the wire does."""
RSS_GROWTH_FLOOR_MIB = 1.0
RSS_GROWTH_MIB_PER_HOUR = 2.0
"""Median RSS of the last quarter of the night (after a 10 % warm-up) minus that of the first
quarter may be at most the larger of 1 MiB (allocator noise) and 2 MiB per real hour between
them. The leak the soak found (~13 MiB/h under this load) failed it in a 30-hour night."""
FD_GROWTH_BOUND = 2
"""Most fds of the last quarter minus most of the first quarter (clients reconnect meanwhile)."""
FINAL_LANDING_BOUND_DEG = 1.0
"""After the faults, a last slew lands within this of its target (the state recovered)."""


@dataclass(frozen=True)
class SoakConfig:
    """One night: its length, speed-up, seed, clients and faults."""

    hours: float = 10.0
    rate: float = 100.0
    seed: int = 1
    alpaca_pollers: int = 2
    dashboards: int = 2
    poll_hz: float = 4.0
    faults_per_kind: int = 6
    fault_kinds: tuple[str, ...] = (
        "drop",
        "short",
        "malformed",
        "slow",
        "delay=1",
        "delay=6",
        "close",
    )
    """How often each probabilistic fault rule fires at most."""
    fault_firings: int = 9
    """The expected firings of each rule while faults are on, were it not limited to
    ``faults_per_kind``: a little more, so that each is used up by the end of the fault phase."""
    wire_commands_per_s: float = 25.0
    """SynScan commands per second assumed for the fault probabilities (~50/s reach the device
    when all is well, far fewer while faults fire)."""
    faults: bool = True
    """False: the same night without faults (for comparison)."""
    faults_until: float = 0.7
    """The fraction of the night after which every fault is cleared (the rest shows recovery)."""
    outages: tuple[tuple[float, str], ...] = ((0.3, "stall"), (0.5, "halt"))
    """(fraction of the night, kind): the device stops answering (stall) or reading (halt)..."""
    outage_s: float = 8.0
    """... for this long, then resumes."""
    scripted: tuple[tuple[float, str], ...] = ()
    """(fraction of the night, fault spec): rules added at set times (``once`` rules fire on the
    next command)."""

    @property
    def real_s(self) -> float:
        return self.hours * 3600.0 / self.rate

    def fault_specs(self) -> list[str]:
        """One rule per fault kind, each firing at most ``faults_per_kind`` times, with the chance
        per wire command that gives ``fault_firings`` over the fault phase."""
        if not self.faults:
            return []
        phase_s = self.faults_until * self.real_s
        probability = min(0.5, self.fault_firings / (phase_s * self.wire_commands_per_s))
        return [
            f"any:{kind}:times={self.faults_per_kind}:p={probability:.5f}"
            for kind in self.fault_kinds
        ]


FULL = SoakConfig()
QUICK = SoakConfig(
    hours=1.0,
    rate=200.0,
    alpaca_pollers=1,
    dashboards=1,
    # One of each kind that costs the wire least, one after the other, early in the night (drop
    # and short cost a timeout each, as the 6 s delay does)
    fault_kinds=(),
    scripted=(
        (0.03, "any:close:once"),
        (0.06, "any:malformed:once"),
        (0.09, "any:slow:once"),
        (0.12, "any:delay=6:once"),
    ),
    faults_until=0.6,
    outages=(),
)


T = TypeVar("T")

# --- what the night records ----------------------------------------------------------------------


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
    guard_stops: list[float] = field(default_factory=list)
    """When serve's horizon guard stopped the mount."""
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


# --- the device: a SynScan emulator in its own process, its faults switched from here -----------


class CountingInjector(FaultInjector):
    """A fault injector that also counts the commands it is asked about (one per command)."""

    def __init__(self, *, seed: int) -> None:
        super().__init__(seed=seed)
        self.commands = 0

    def select(self, command: str) -> Fault | None:
        self.commands += 1
        return super().select(command)


async def emulate(rate: float, seed: int) -> None:
    """The ``--emulator`` role: what ``scopelink emulate synscan --tcp 127.0.0.1:0 --clock-rate
    RATE`` runs (EQ6, 9600 baud pacing, Greenwich), with its faults switched by lines on stdin:
    ``add SPEC`` (a ``--fault`` spec), ``clear`` (remove every rule, end a stall or halt),
    ``resume`` (end a stall or halt), ``count`` (prints ``commands N``). Fired faults are logged
    as ``scopelink emulate`` logs them."""
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(name)s %(message)s")
    logging.getLogger("scopelink.servers.faults").setLevel(logging.INFO)
    faults = CountingInjector(seed=seed)
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock(rate=rate))
    config = SynScanConfig(model=EQ6.synscan_model_code or 0)
    loop = asyncio.get_running_loop()
    stdin = asyncio.StreamReader()
    await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(stdin), sys.stdin)
    async with SynScanEmulator(mount, config, faults=faults, wire=SERIAL_9600_8N1) as device:
        await device.on_tcp("127.0.0.1", 0)
        print(f"synscan emulator listening on {device.address}", flush=True)
        loop.add_signal_handler(signal.SIGTERM, stdin.feed_eof)  # stop as 'scopelink emulate' does
        while line := (await stdin.readline()).decode().strip():
            verb, _, argument = line.partition(" ")
            match verb:
                case "add":
                    faults.add(Fault.parse(argument))
                case "clear":
                    faults.clear()
                case "resume":
                    faults.resume()
                case "count":
                    print(f"commands {faults.commands}", flush=True)


class Emulator:
    """The bench's end of the ``--emulator`` process."""

    def __init__(self, process: asyncio.subprocess.Process) -> None:
        self.process = process

    async def say(self, line: str) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write(f"{line}\n".encode())
        await self.process.stdin.drain()

    async def commands(self) -> int:
        await self.say("count")
        assert self.process.stdout is not None
        async with asyncio.timeout(5):
            line = (await self.process.stdout.readline()).decode()
        return int(line.split()[1])


async def _start_emulator(config: SoakConfig, home: Path) -> tuple[Emulator, int]:
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "bench.soak",
        "--emulator",
        "--rate",
        f"{config.rate:g}",
        "--seed",
        str(config.seed),
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
        env=environment(home),
        cwd=ROOT,
    )
    printed = await _read_until(process, lambda line: "listening on" in line)
    found = re.search(r"127\.0\.0\.1:(\d+)", printed)
    assert found is not None
    return Emulator(process), int(found.group(1))


# --- the processes -------------------------------------------------------------------------------


async def _read_until(process: asyncio.subprocess.Process, last: Callable[[str], bool]) -> str:
    assert process.stdout is not None
    assert process.stderr is not None
    lines: list[str] = []
    async with asyncio.timeout(30):
        while not lines or not last(lines[-1]):
            line = (await process.stdout.readline()).decode()
            if not line:
                errors = (await process.stderr.read()).decode()
                raise RuntimeError(f"scopelink exited early: {lines} {errors[-2000:]}")
            lines.append(line.rstrip("\n"))
    return "\n".join(lines)


_FIRES = re.compile(r"^(\S+ \S+) \S+ fault \w+:(\w+)(=[\d.]+)?:\S* fires on '(.*)'$")


async def _watch_emulator_log(process: asyncio.subprocess.Process, night: Night) -> None:
    """The emulator logs every fault that fires, stamped with its wall clock."""
    assert process.stderr is not None
    while line := (await process.stderr.readline()).decode(errors="replace"):
        if found := _FIRES.search(line.rstrip()):
            # logging's asctime: local time to the millisecond
            stamp = datetime.strptime(found.group(1), "%Y-%m-%d %H:%M:%S,%f").astimezone(UTC)
            night.fault_stamps.append((stamp, found.group(2) + (found.group(3) or "")))


async def _watch_serve_log(process: asyncio.subprocess.Process, night: Night) -> None:
    assert process.stderr is not None
    while line := (await process.stderr.readline()).decode(errors="replace"):
        night.serve_log.append(f"{night.now():7.1f} s {line.rstrip()}")
        if "was stopped at" in line:
            night.guard_stops.append(night.now())


async def _stop(process: asyncio.subprocess.Process) -> int:
    if process.returncode is None:
        process.send_signal(signal.SIGTERM)
    try:
        async with asyncio.timeout(15):
            return await process.wait()
    except TimeoutError:
        process.kill()
        return await process.wait()


def _rss_kib_and_fds(pid: int) -> tuple[int, int]:
    status = Path(f"/proc/{pid}/status").read_text()
    found = re.search(r"^VmRSS:\s+(\d+) kB", status, re.MULTILINE)
    return (int(found.group(1)) if found else 0), len(os.listdir(f"/proc/{pid}/fd"))


_TCP_STATES = {"01": "established", "06": "time-wait", "08": "close-wait", "0A": "listen"}


def _open_files(pid: int) -> Counter[str]:
    """What the process holds open, by kind: TCP sockets (listening, a client's, the device
    link's), pipes, event fds, files."""
    rows: list[tuple[int, int, str, str]] = []  # local port, remote port, state, inode
    for table in ("tcp", "tcp6"):
        with contextlib.suppress(OSError):
            for line in Path(f"/proc/{pid}/net/{table}").read_text().splitlines()[1:]:
                fields = line.split()
                local, remote = int(fields[1].split(":")[1], 16), int(fields[2].split(":")[1], 16)
                rows.append((local, remote, _TCP_STATES.get(fields[3], fields[3]), fields[9]))
    listening = {local for local, _, state, _ in rows if state == "listen"}
    sockets: dict[str, str] = {}
    for local, remote, state, inode in rows:
        if state == "listen":
            sockets[inode] = f"listening on :{local}"
        elif local in listening:
            sockets[inode] = f"{state} client of :{local}"
        else:
            sockets[inode] = f"{state} to :{remote}"  # the device link
    kinds: Counter[str] = Counter()
    for fd in os.listdir(f"/proc/{pid}/fd"):
        with contextlib.suppress(OSError):
            target = os.readlink(f"/proc/{pid}/fd/{fd}")
            if target.startswith("socket:["):
                target = "socket " + sockets.get(target[8:-1], "(not tcp)")
            elif target.startswith("pipe:["):
                target = "pipe"
            kinds[target] += 1
    return kinds


async def _sample_memory(pid: int, night: Night) -> None:
    while True:
        rss, fds = _rss_kib_and_fds(pid)
        night.memory.append((night.now(), rss, fds))
        await asyncio.sleep(1.0)


def _listening(printed: str, label: str) -> int:
    found = re.search(label + r"\s+(?:tcp |http://)?127\.0\.0\.1:(\d+)", printed)
    if found is None:
        raise RuntimeError(f"serve printed no {label} port: {printed}")
    return int(found.group(1))


@dataclass(frozen=True)
class Ports:
    alpaca: int
    lx200: int
    stellarium: int
    synscan: int
    dashboard: int


# --- targets -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Target:
    alt_deg: float
    az_deg: float
    ra_of_date_hours: float
    dec_of_date_deg: float
    ra_j2000_hours: float
    dec_j2000_deg: float


def random_target(chance: random.Random) -> Target:
    """A position well above the horizon now (real time: what the driver checks against)."""
    alt = chance.uniform(LOWEST_TARGET_ALT_DEG, 80.0)
    az = chance.uniform(0.0, 360.0)
    now = datetime.now(UTC)
    ra, dec = observed_to_apparent(alt, az, now, SITE)
    ra_j2000, dec_j2000 = observed_to_j2000(alt, az, now, SITE)
    return Target(alt, az, ra, dec, ra_j2000, dec_j2000)


def separation_deg(ra1_h: float, dec1: float, ra2_h: float, dec2: float) -> float:
    a1, d1, a2, d2 = map(math.radians, (ra1_h * 15, dec1, ra2_h * 15, dec2))
    cosine = math.sin(d1) * math.sin(d2) + math.cos(d1) * math.cos(d2) * math.cos(a1 - a2)
    return math.degrees(math.acos(max(-1.0, min(1.0, cosine))))


# --- the clients ---------------------------------------------------------------------------------


class Alpaca:
    """An Alpaca client on one keep-alive HTTP session."""

    def __init__(self, session: aiohttp.ClientSession, port: int, night: Night) -> None:
        self._session = session
        self._base = f"http://127.0.0.1:{port}/api/v1/telescope/0"
        self._night = night
        self._transaction = 0

    async def _request(self, method: str, member: str, form: dict[str, str]) -> Any:
        self._transaction += 1
        params = {"ClientID": "7", "ClientTransactionID": str(self._transaction)}
        url = f"{self._base}/{member}"
        if method == "GET":
            response = self._session.get(url, params={**params, **form})
        else:
            response = self._session.put(url, data={**params, **form})
        async with response as answer:
            answer.raise_for_status()
            reply: dict[str, Any] = await answer.json()
        if reply.get("ErrorNumber", 0) != 0:
            self._night.answered_error("alpaca", str(reply.get("ErrorMessage")))
            return None
        return reply.get("Value")

    async def get(self, member: str) -> Any:
        work = self._request("GET", member, {})
        try:
            return await self._night.timed("alpaca", f"GET {member}", READ_BOUND_S, work)
        except aiohttp.ClientError as error:
            self._night.broken.append(f"alpaca GET {member} at {self._night.now():.1f} s: {error}")
            return None

    async def put(self, member: str, **form: str) -> bool:
        """True when the device accepted the command (errors are answers too, and counted)."""
        work = self._request("PUT", member, form)
        before = self._night.of("alpaca").errors
        try:
            await self._night.timed("alpaca", f"PUT {member}", COMMAND_BOUND_S, work)
        except aiohttp.ClientError as error:
            self._night.broken.append(f"alpaca PUT {member} at {self._night.now():.1f} s: {error}")
            return False
        return self._night.of("alpaca").errors == before


async def alpaca_poller(alpaca: Alpaca, night: Night, period_s: float) -> None:
    """Reads what an imaging program's mount panel shows, several times a second."""
    while True:
        for member in ("rightascension", "declination", "slewing", "tracking"):
            with contextlib.suppress(TimeoutError):
                await alpaca.get(member)
        await asyncio.sleep(period_s)


async def wait_until_still(alpaca: Alpaca, night: Night, what: str) -> float | None:
    """Seconds until Alpaca says Slewing false, or None (recorded as stuck) past the bound."""
    start = night.now()
    while night.now() - start < SLEW_BOUND_S:
        with contextlib.suppress(TimeoutError):
            if await alpaca.get("slewing") is False:
                return night.now() - start
        await asyncio.sleep(0.1)
    night.stuck.append(f"{what} at {start:.1f} s: still slewing after {SLEW_BOUND_S:g} s")
    return None


async def alpaca_commander(alpaca: Alpaca, night: Night, chance: random.Random) -> None:
    """Slews, aborts, tracking on and off, MoveAxis, park and unpark, in a random order."""
    await alpaca.put("connected", Connected="True")
    await alpaca.put("tracking", Tracking="True")
    while True:
        action = chance.choices(
            ["slew", "abort", "tracking", "move", "park"], weights=[5, 2, 2, 2, 1]
        )[0]
        with contextlib.suppress(TimeoutError):
            await _alpaca_action(action, alpaca, night, chance)
        await asyncio.sleep(chance.uniform(0.3, 1.5))


async def _alpaca_action(action: str, alpaca: Alpaca, night: Night, chance: random.Random) -> None:
    match action:
        case "slew" | "abort":
            target = random_target(chance)
            night.moved("Alpaca slew")
            accepted = await alpaca.put(
                "slewtocoordinatesasync",
                RightAscension=f"{target.ra_of_date_hours:.6f}",
                Declination=f"{target.dec_of_date_deg:.5f}",
            )
            if action == "abort":
                await asyncio.sleep(chance.uniform(0.0, 0.3))
                night.moved("Alpaca abort")
                await alpaca.put("abortslew")
            if accepted:
                night.slews += 1
                took = await wait_until_still(alpaca, night, f"Alpaca {action}")
                if took is not None:
                    night.slew_times.append(took)
        case "tracking":
            await alpaca.put("tracking", Tracking="False")
            await asyncio.sleep(chance.uniform(0.5, 2.0))  # the x100 sky turns 0.4 deg/s meanwhile
            await alpaca.put("tracking", Tracking="True")
        case "move":
            # 0.05 deg/s in the emulator's x100 time: 5 deg/s real for a fraction of a second
            rate = chance.choice(["0.05", "-0.05"])
            night.moved("Alpaca MoveAxis")
            if await alpaca.put("moveaxis", Axis=str(chance.randrange(2)), Rate=rate):
                await asyncio.sleep(chance.uniform(0.1, 0.5))
                night.moved("Alpaca MoveAxis stop")
                await alpaca.put("moveaxis", Axis="0", Rate="0")
                await alpaca.put("moveaxis", Axis="1", Rate="0")
                await wait_until_still(alpaca, night, "Alpaca MoveAxis stop")
        case "park":
            night.moved("Alpaca park")
            if await alpaca.put("park"):
                await wait_until_still(alpaca, night, "Alpaca park")
            await asyncio.sleep(chance.uniform(0.5, 2.0))
            await alpaca.put("unpark")
            await alpaca.put("tracking", Tracking="True")


async def lx200_client(port: int, night: Night, chance: random.Random, period_s: float) -> None:
    """SkySafari-like: :GR#/:GD# polling, now and then a goto (:Sr :Sd :MS#) or :Q#; one
    connection of 20-40 s."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    night.reconnects["lx200"] += 1
    try:
        connected_until = night.now() + chance.uniform(20.0, 40.0)
        behind_a_command = False
        while night.now() < connected_until:
            for command in (b":GR#", b":GD#"):
                writer.write(command)
                work = reader.readuntil(b"#")
                if behind_a_command:
                    # LX200 answers in order: this read waits for the :Q# before it to reach
                    # the device (through any fault)
                    await night.timed(
                        "lx200", f"{command.decode()} after :Q#", COMMAND_BOUND_S, work
                    )
                else:
                    await night.timed("lx200", command.decode(), READ_BOUND_S, work)
            behind_a_command = False
            roll = chance.random()
            if roll < 0.03:
                await _lx200_goto(reader, writer, night, chance)
            elif roll < 0.04:
                night.moved("LX200 :Q#")
                writer.write(b":Q#")  # no reply
                night.of("lx200").count += 1
                behind_a_command = True
            await asyncio.sleep(period_s)
    finally:
        writer.close()
        with contextlib.suppress(OSError):
            await writer.wait_closed()


async def _lx200_goto(
    reader: asyncio.StreamReader,
    writer: asyncio.StreamWriter,
    night: Night,
    chance: random.Random,
) -> None:
    target = random_target(chance)
    for command in (
        f":Sr{format_ra(target.ra_of_date_hours)}#",
        f":Sd{format_dec(target.dec_of_date_deg)}#",
    ):
        writer.write(command.encode())
        accepted = await night.timed("lx200", command[:3], READ_BOUND_S, reader.readexactly(1))
        if accepted != b"1":
            night.answered_error("lx200", f"{command[:3]} refused")
    night.moved("LX200 :MS#")
    writer.write(b":MS#")
    reply = await night.timed("lx200", ":MS#", COMMAND_BOUND_S, reader.readexactly(1))
    if reply != b"0":
        reason = await night.timed("lx200", ":MS# reason", READ_BOUND_S, reader.readuntil(b"#"))
        night.answered_error("lx200", f":MS# {reply.decode()} {reason.decode(errors='replace')}")
    else:
        night.slews += 1


async def stellarium_client(port: int, night: Night, chance: random.Random, *, gotos: bool) -> None:
    """Reads the position stream (24-byte messages every 0.5 s), with ``gotos`` sends a goto now
    and then; one connection of 20-40 s."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    night.reconnects["stellarium"] += 1
    try:
        connected_until = night.now() + chance.uniform(20.0, 40.0)
        last = night.now()
        while night.now() < connected_until:
            message = await night.timed(
                "stellarium", "position", STREAM_GAP_BOUND_S, reader.readexactly(24)
            )
            length, kind = struct.unpack_from("<HH", message)
            if (length, kind) != (24, 0):
                night.answered_error("stellarium", f"message {length} {kind}")
            night.stream_gaps.append(night.now() - last)
            last = night.now()
            if gotos and chance.random() < 0.04:
                target = random_target(chance)
                goto = GotoMessage.from_degrees(target.ra_j2000_hours, target.dec_j2000_deg)
                night.moved("Stellarium goto")
                writer.write(goto.encode())
                night.of("stellarium").count += 1
    finally:
        writer.close()
        with contextlib.suppress(OSError):
            await writer.wait_closed()


async def synscan_client(port: int, night: Night, period_s: float) -> None:
    """A planetarium on our SynScan server: ``e`` polls; one connection of 30 s."""
    async with await open_tcp("127.0.0.1", port) as link:
        night.reconnects["synscan"] += 1
        client = SynScanClientConnection()
        connected_until = night.now() + 30.0
        while night.now() < connected_until:
            await link.write(client.send(GetRaDec(precise=True)))

            async def reply(client: SynScanClientConnection = client) -> object:
                while (event := client.next_event()) is NEED_DATA:
                    client.receive_data(await link.read())
                return event

            event = await night.timed("synscan", "e", READ_BOUND_S, reply())
            if not isinstance(event, Position):
                night.answered_error("synscan", type(event).__name__)
                if not isinstance(event, AnyReply):
                    break
            await asyncio.sleep(period_s)


async def dashboard_observer(session: aiohttp.ClientSession, port: int, night: Night) -> None:
    """A dashboard page: every update's read_at (the poller's pulse) and slewing flag."""
    async with session.ws_connect(f"http://127.0.0.1:{port}/ws") as ws:
        night.reconnects["dashboard"] += 1
        last_read_at = ""
        async for message in ws:
            if message.type is not aiohttp.WSMsgType.TEXT:
                break
            night.of("dashboard").count += 1
            state = message.json().get("state")
            if state is None:
                continue
            if state["read_at"] != last_read_at:
                last_read_at = state["read_at"]
                night.reading_advances.append(night.at(datetime.fromisoformat(last_read_at)))
            night.slewing_samples.append((night.now(), bool(state["slewing"])))
            problems = [str(problem) for problem in state["problems"]]
            failed = any("poll failed" in problem for problem in problems)
            night.poll_failed_samples.append((night.now(), failed))
            night.last_problems = problems
    night.broken.append(f"dashboard page closed by the server at {night.now():.1f} s")


async def dashboard_churn(session: aiohttp.ClientSession, port: int, night: Night) -> None:
    """A page opened and closed again: a hello and a few updates, then 3 s away."""
    async with session.ws_connect(f"http://127.0.0.1:{port}/ws") as ws:
        night.reconnects["dashboard"] += 1
        for _ in range(3):
            await night.timed("dashboard", "update", READ_BOUND_S, ws.receive())
            night.of("dashboard").count += 1
    await asyncio.sleep(3.0)


async def reconnecting(
    protocol: str, night: Night, connection: Callable[[], Awaitable[None]]
) -> None:
    """One client connection after another, as long as the night lasts. A connection that
    breaks is recorded (a late reply already is, by :meth:`Night.timed`) and replaced."""
    while True:
        try:
            await connection()
        except TimeoutError:
            pass  # a reply came too late: recorded; a new connection starts from a clean stream
        except (OSError, EOFError, LinkError, aiohttp.ClientError) as error:
            night.broken.append(f"{protocol} at {night.now():.1f} s: {error!r}")
        await asyncio.sleep(0.2)


# --- the night -----------------------------------------------------------------------------------


@dataclass
class Check:
    name: str
    passed: bool
    detail: str


@dataclass
class SoakReport:
    config: SoakConfig
    night: Night
    checks: list[Check]
    baseline_files: Counter[str]
    """What serve held open before any client came (by kind, see :func:`_open_files`)."""
    final_files: Counter[str]
    """What it held open a few seconds after the last client left."""
    exit_codes: tuple[int, int]

    @property
    def passed(self) -> bool:
        return all(check.passed for check in self.checks)


@contextlib.asynccontextmanager
async def _running(tasks: list[asyncio.Task[None]]) -> AsyncIterator[None]:
    try:
        yield
    finally:
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)


async def _start_serve(home: Path, device_port: int) -> tuple[asyncio.subprocess.Process, str]:
    """``scopelink serve`` on the emulated device, every server on a free port; what it printed."""
    serve = await start_scopelink(
        home,
        "serve",
        "--device",
        f"synscan:tcp://127.0.0.1:{device_port}",
        "--alpaca-port=0",
        "--discovery-port=-1",
        "--lx200-port=0",
        "--skyfi-port=-1",
        "--stellarium-port=0",
        "--synscan-port=0",
        "--dashboard-port=0",
    )
    try:
        return serve, await _read_until(serve, lambda line: line == "Ctrl-C stops.")
    except BaseException:
        await _stop(serve)
        raise


async def run_soak(config: SoakConfig) -> SoakReport:
    night = Night(started=asyncio.get_running_loop().time())
    chance = random.Random(config.seed)
    with tempfile.TemporaryDirectory(prefix="scopelink-soak-") as home_text:
        home = Path(home_text)
        emulator, device_port = await _start_emulator(config, home)
        serve: asyncio.subprocess.Process | None = None
        logs = [asyncio.create_task(_watch_emulator_log(emulator.process, night))]
        try:
            serve, printed = await _start_serve(home, device_port)
            ports = Ports(
                alpaca=_listening(printed, "Alpaca"),
                lx200=_listening(printed, "LX200"),
                stellarium=_listening(printed, "Stellarium"),
                synscan=_listening(printed, "SynScan"),
                dashboard=_listening(printed, "Dashboard"),
            )
            logs.append(asyncio.create_task(_watch_serve_log(serve, night)))
            await asyncio.sleep(1.0)
            baseline_files = _open_files(serve.pid)
            sampler = asyncio.create_task(_sample_memory(serve.pid, night))
            async with aiohttp.ClientSession() as session:
                await _night_of_clients(
                    config, night, chance=chance, session=session, ports=ports, emulator=emulator
                )
            night.wire_commands = await emulator.commands()
            await asyncio.sleep(2.0)  # closed connections are reaped
            final_files = _open_files(serve.pid)
            sampler.cancel()
        finally:
            codes = (await _stop(serve) if serve is not None else -1, await _stop(emulator.process))
        await asyncio.gather(*logs, return_exceptions=True)
    report = SoakReport(config, night, [], baseline_files, final_files, codes)
    report.checks = judge(report)
    return report


async def _night_of_clients(
    config: SoakConfig,
    night: Night,
    *,
    chance: random.Random,
    session: aiohttp.ClientSession,
    ports: Ports,
    emulator: Emulator,
) -> None:
    """Every client at once for the night, the faults switched on and off as ``config`` says;
    then, with the observers still watching, the actors stop and one last slew shows that the
    state recovered."""
    period = 1.0 / config.poll_hz
    alpaca = Alpaca(session, ports.alpaca, night)
    await alpaca.put("connected", Connected="True")  # Alpaca clients connect before anything
    loop = asyncio.get_running_loop()
    random_target(chance)  # the first conversion loads ERFA's tables: not during the night
    night.started = loop.time()  # the night's clock starts with its clients
    night.started_wall = datetime.now(UTC)

    def start(work: Coroutine[Any, Any, None]) -> asyncio.Task[None]:
        return asyncio.create_task(work)

    observers = [
        start(
            reconnecting(
                "dashboard", night, lambda: dashboard_observer(session, ports.dashboard, night)
            )
        )
        for _ in range(config.dashboards)
    ]
    observers.append(
        start(
            reconnecting(
                "dashboard", night, lambda: dashboard_churn(session, ports.dashboard, night)
            )
        )
    )
    for _ in range(config.alpaca_pollers):
        observers.append(start(alpaca_poller(Alpaca(session, ports.alpaca, night), night, period)))
    readers = random.Random(chance.random())
    observers.append(
        start(
            reconnecting(
                "stellarium",
                night,
                lambda: stellarium_client(ports.stellarium, night, readers, gotos=False),
            )
        )
    )
    observers.append(
        start(reconnecting("synscan", night, lambda: synscan_client(ports.synscan, night, period)))
    )
    lx200_chance, stellarium_chance = _child(chance), _child(chance)
    actors = [
        start(alpaca_commander(alpaca, night, _child(chance))),
        start(
            reconnecting(
                "lx200", night, lambda: lx200_client(ports.lx200, night, lx200_chance, period)
            )
        ),
        start(
            reconnecting(
                "stellarium",
                night,
                lambda: stellarium_client(ports.stellarium, night, stellarium_chance, gotos=True),
            )
        ),
    ]
    actors.append(start(fault_schedule(config, night, emulator)))
    async with _running(observers):
        async with _running(actors):
            end = night.started + config.real_s
            while loop.time() < end:
                for task in (*observers, *actors):
                    if task.done() and not task.cancelled() and task.exception() is not None:
                        raise RuntimeError(f"a client died: {task.exception()!r}")
                await asyncio.sleep(min(1.0, max(0.0, end - loop.time())))
        await _final_slew(alpaca, night, chance)
        await asyncio.sleep(1.0)  # the observers see the state after it


async def fault_schedule(config: SoakConfig, night: Night, emulator: Emulator) -> None:
    """Faults on from the start of the night; outages (a stall: the device reads but never
    answers; a halt: it stops reading) at set times; every fault off at ``faults_until``."""
    if not config.faults:
        return
    for spec in config.fault_specs():
        await emulator.say(f"add {spec}")
    events = sorted(
        [(at * config.real_s, f"add {spec}") for at, spec in config.scripted]
        + [(at * config.real_s, f"add any:{kind}:once") for at, kind in config.outages]
        + [((at * config.real_s) + config.outage_s, "resume") for at, _ in config.outages]
        + [(config.faults_until * config.real_s, "clear")]
    )
    for at, line in events:
        await asyncio.sleep(max(0.0, at - night.now()))
        await emulator.say(line)
        night.fault_switches.append((night.now(), line))
    night.faults_cleared_at = night.now()


def _child(chance: random.Random) -> random.Random:
    return random.Random(chance.random())


async def _final_slew(alpaca: Alpaca, night: Night, chance: random.Random) -> None:
    """One more slew once the faults are over; its outcome goes to ``night.final_landing`` (a
    request without an answer is recorded as late and leaves the landing unknown)."""
    with contextlib.suppress(TimeoutError):
        await _final_slew_steps(alpaca, night, chance)


async def _final_slew_steps(alpaca: Alpaca, night: Night, chance: random.Random) -> None:
    await alpaca.put("unpark")
    await alpaca.put("tracking", Tracking="True")
    target = random_target(chance)
    night.moved("final slew")
    await alpaca.put(
        "slewtocoordinatesasync",
        RightAscension=f"{target.ra_of_date_hours:.6f}",
        Declination=f"{target.dec_of_date_deg:.5f}",
    )
    took = await wait_until_still(alpaca, night, "final slew")
    # The landing reading at once: the x100 sky moves 0.4 deg/s under a mount that stopped tracking
    ra, dec = await alpaca.get("rightascension"), await alpaca.get("declination")
    miss = separation_deg(ra, dec, target.ra_of_date_hours, target.dec_of_date_deg)
    night.final_landing = (took, miss)


# --- the checks ----------------------------------------------------------------------------------


def _longest_gap(times: list[float], start: float, end: float) -> tuple[float, float]:
    """The longest stretch of [start, end] without any of ``times``: (length, its start)."""
    points = [start, *(t for t in times if start <= t <= end), end]
    return max((b - a, a) for a, b in itertools.pairwise(points))


def _longest_slewing_after_command(night: Night) -> tuple[float, str]:
    """The longest time Slewing stayed true after the latest motion command before it, and
    that command (what, when)."""
    longest, which = 0.0, "none"
    since: float | None = None
    for at, slewing in night.slewing_samples:
        if not slewing:
            since = None
            continue
        commanded, what = max(
            ((t, w) for t, w in night.motion_commands if t <= at), default=(0.0, "none")
        )
        since = at if since is None else since
        if at - max(since, commanded) > longest:
            longest = at - max(since, commanded)
            which = f"{what} at {commanded:.1f} s"
    return longest, which


def _quarters(values: list[tuple[float, int, int]], warm_up_s: float) -> tuple[list[int], ...]:
    settled = [v for v in values if v[0] >= warm_up_s]
    quarter = max(1, len(settled) // 4)
    first, last = settled[:quarter], settled[-quarter:]
    return [v[1] for v in first], [v[1] for v in last], [v[2] for v in first], [v[2] for v in last]


def fault_spans(night: Night, end: float) -> list[tuple[float, float]]:
    """(start, end) of every fault: a stall or halt ends when it is resumed, any other fault when
    it fires."""
    resumes = [at for at, line in night.fault_switches if line in {"resume", "clear"}]
    spans: list[tuple[float, float]] = []
    for at, kind in night.faults:
        ends = at
        if kind in {"stall", "halt"}:
            ends = min((t for t in resumes if t >= at), default=end)
        spans.append((at, ends))
    return spans


def quiet_windows(night: Night, end: float) -> list[tuple[float, float]]:
    """Stretches without faults, from ``QUIET_SETTLE_S`` after a fault ended to the next fault
    (or the end), long enough to judge."""
    windows: list[tuple[float, float]] = []
    quiet_from = 0.0
    for starts, ends in sorted(fault_spans(night, end)):
        if starts - quiet_from >= QUIET_WINDOW_MIN_S:
            windows.append((quiet_from, starts))
        quiet_from = max(quiet_from, ends + QUIET_SETTLE_S)
    if end - quiet_from >= QUIET_WINDOW_MIN_S:
        windows.append((quiet_from, end))
    return windows


def _recovery(night: Night, end: float) -> tuple[int, list[str], float]:
    """(quiet windows judged, those that did not recover, longest reading gap inside them)."""
    windows = quiet_windows(night, end)
    failures: list[str] = []
    worst = 0.0
    for a, b in windows:
        gap, gap_at = _longest_gap(night.reading_advances, a, b)
        worst = max(worst, gap)
        failed = [f for t, f in night.poll_failed_samples if a <= t <= b]
        if gap > QUIET_POLL_GAP_BOUND_S:
            failures.append(
                f"{a:.0f}-{b:.0f} s: a gap of {gap:.1f} s between readings from {gap_at:.1f} s"
            )
        if failed and all(failed):
            failures.append(f"{a:.0f}-{b:.0f} s: the failed poll stayed among the problems")
    return len(windows), failures, worst


def _files_text(files: Counter[str]) -> str:
    return ", ".join(f"{n}x {kind}" for kind, n in sorted(files.items())) or "nothing"


def judge(report: SoakReport) -> list[Check]:
    night, config = report.night, report.config
    end = config.real_s
    unanswered = [late for record in night.requests.values() for late in record.late]
    unanswered += night.broken
    spans = fault_spans(night, end)
    unanswered += [
        f"{what}: no answer outside a fault"
        for at, what in night.withheld
        if not any(start <= at <= ends + QUIET_SETTLE_S for start, ends in spans)
    ]
    gap, gap_at = _longest_gap(night.reading_advances, 1.0, end)
    gap_bound = POLL_GAP_BOUND_S + (config.outage_s if config.faults and config.outages else 0.0)
    windows, not_recovered, quiet_gap = _recovery(night, end)
    slewing_for, slewing_after = _longest_slewing_after_command(night)
    stream_gap = max(night.stream_gaps, default=0.0)
    rss_first, rss_last, fds_first, fds_last = _quarters(night.memory, warm_up_s=0.1 * end)
    rss_growth_mib = (statistics.median(rss_last) - statistics.median(rss_first)) / 1024
    settled = [(t, rss) for t, rss, _ in night.memory if t >= 0.1 * end]
    trend = statistics.linear_regression([t for t, _ in settled], [rss for _, rss in settled])
    trend_mib_per_hour = trend.slope * 3600 / 1024  # per real hour: the load runs in real time
    quarters_apart_h = 0.75 * (end - 0.1 * end) / 3600  # between the quarters' middles
    rss_bound_mib = max(RSS_GROWTH_FLOOR_MIB, RSS_GROWTH_MIB_PER_HOUR * quarters_apart_h)
    fd_growth = max(fds_last) - max(fds_first)
    took, miss = night.final_landing
    # The horizon guard's notice is a problem shown on purpose, not a failure to recover
    failures_after = [p for p in night.last_problems if "was stopped at" not in p]
    kinds = {spec.split(":")[1] for spec in config.fault_specs()}
    if config.faults:
        kinds |= {spec.split(":")[1] for _, spec in config.scripted}
        kinds |= {kind for _, kind in config.outages}
    fired = {kind for _, kind in night.faults}
    left_open = report.final_files - report.baseline_files
    data_files = Counter({kind: n for kind, n in left_open.items() if kind.startswith("/")})
    left_open -= data_files
    return [
        Check(
            "every fault kind fired",
            fired == kinds,
            f"{len(night.faults)} faults; kinds never fired: "
            f"{', '.join(sorted(kinds - fired)) or 'none'}",
        ),
        Check(
            "no request unanswered, no connection broken",
            not unanswered,
            "; ".join(unanswered[:3])
            or "every request answered within its bound"
            + (
                f" ({len(night.withheld)} position reads withheld during faults: the reading "
                "was stale)"
                if night.withheld
                else ""
            ),
        ),
        Check(
            "no stuck slew",
            not night.stuck and slewing_for <= SLEW_BOUND_S,
            "; ".join(night.stuck[:3])
            or f"longest Slewing after a motion command {slewing_for:.1f} s <= {SLEW_BOUND_S:g} s "
            f"({slewing_after})",
        ),
        Check(
            "poller never stops",
            gap <= gap_bound,
            f"longest gap between readings {gap:.1f} s <= {gap_bound:g} s (from {gap_at:.1f} s)",
        ),
        Check(
            "recovers after faults",
            windows > 0 and not not_recovered,
            "; ".join(not_recovered[:3])
            or f"{windows} quiet windows, longest gap in them {quiet_gap:.2f} s "
            f"<= {QUIET_POLL_GAP_BOUND_S:g} s, failed polls cleared in each",
        ),
        Check(
            "final slew lands",
            took is not None and miss <= FINAL_LANDING_BOUND_DEG and not failures_after,
            f"{'stuck' if took is None else f'{took:.1f} s'}, {miss:.3f}° from its target "
            f"<= {FINAL_LANDING_BOUND_DEG:g}°; problems after it: {night.last_problems or 'none'}",
        ),
        Check(
            "Stellarium stream steady",
            stream_gap <= STREAM_GAP_BOUND_S,
            f"longest gap between positions {stream_gap:.2f} s <= {STREAM_GAP_BOUND_S:g} s",
        ),
        Check(
            "memory flat",
            rss_growth_mib <= rss_bound_mib,
            f"RSS median first quarter {statistics.median(rss_first) / 1024:.1f} MiB, last "
            f"{statistics.median(rss_last) / 1024:.1f} MiB: {rss_growth_mib:+.2f} MiB "
            f"<= {rss_bound_mib:.2f}; trend {trend_mib_per_hour:+.2f} MiB per hour",
        ),
        Check(
            "fds flat, back to baseline",
            fd_growth <= FD_GROWTH_BOUND and not left_open,
            f"most fds first quarter {max(fds_first)}, last {max(fds_last)}; "
            f"{report.baseline_files.total()} before the clients, "
            f"{report.final_files.total()} after; left open: {_files_text(left_open)} "
            f"(data files opened once and kept: {_files_text(data_files)})",
        ),
        Check(
            "clean exits",
            report.exit_codes == (0, 0),
            f"serve {report.exit_codes[0]}, emulator {report.exit_codes[1]}",
        ),
    ]


def print_report(report: SoakReport) -> None:
    night, config = report.night, report.config
    print(
        f"soak: {config.hours:g} simulated hours at x{config.rate:g} = {config.real_s:.0f} s real, "
        f"seed {config.seed}"
    )
    print(f"serve before the clients: {_files_text(report.baseline_files)}")
    print(f"{'protocol':<12}{'requests':>10}{'errors':>8}{'slowest s':>11}{'late':>6}  slowest")
    for name, record in sorted(night.requests.items()):
        print(
            f"{name:<12}{record.count:>10}{record.errors:>8}"
            f"{record.slowest_s:>11.2f}{len(record.late):>6}  {record.slowest}"
        )
    print(
        f"wire commands (emulator) {night.wire_commands}, "
        f"{night.wire_commands / config.real_s:.1f}/s"
    )
    kinds = Counter(kind for _, kind in night.faults)
    print(
        f"faults fired {len(night.faults)}: "
        + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items()))
    )
    print(f"slews {night.slews}; slew times " + _spread(night.slew_times))
    print(
        "fault switches "
        + ", ".join(f"{line} at {at:.0f} s" for at, line in night.fault_switches if line != "add")
    )
    print(
        "client connections " + ", ".join(f"{k} {n}" for k, n in sorted(night.reconnects.items()))
    )
    print(
        "answered errors "
        + (", ".join(f"{n}x {t}" for t, n in night.error_texts.most_common(6)) or "none")
    )
    after_motion = sum(
        any(0.0 <= stop - t <= 3.0 for t, _ in night.motion_commands) for stop in night.guard_stops
    )
    print(
        f"horizon guard stops {len(night.guard_stops)}, {after_motion} of them within 3 s of a "
        "motion command"
    )
    print(
        f"serve log lines {len(night.serve_log)}"
        + "".join(f"\n  {line}" for line in night.serve_log[-5:])
    )
    tenths = [
        [
            rss
            for t, rss, _ in night.memory
            if k * config.real_s / 10 <= t < (k + 1) * config.real_s / 10
        ]
        for k in range(10)
    ]
    print(
        "serve RSS MiB by tenth of the night (median): "
        + " ".join(f"{statistics.median(tenth) / 1024:.1f}" for tenth in tenths if tenth)
    )
    for check in report.checks:
        print(f"check {check.name}: {'ok' if check.passed else 'FAIL'} - {check.detail}")
    print(f"soak {'PASSED' if report.passed else 'FAILED'}")


def _spread(values: list[float]) -> str:
    if not values:
        return "none"
    ordered = sorted(values)
    return (
        f"median {statistics.median(ordered):.2f} s, "
        f"p95 {ordered[int(0.95 * (len(ordered) - 1))]:.2f} s, max {ordered[-1]:.2f} s"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description="a simulated night under load and faults")
    parser.add_argument("--hours", type=float, default=FULL.hours, help="simulated hours")
    parser.add_argument("--rate", type=float, default=FULL.rate, help="simulated time speed-up")
    parser.add_argument("--seed", type=int, default=FULL.seed, help="faults and client choices")
    parser.add_argument("--quick", action="store_true", help="1 hour at x200 (the test's run)")
    parser.add_argument("--no-faults", action="store_true", help="the same night without faults")
    parser.add_argument("--emulator", action="store_true", help=argparse.SUPPRESS)  # the device
    args = parser.parse_args()
    if args.emulator:
        # Paced replies keep time on the precise loop, as in 'scopelink emulate'
        with asyncio.Runner(loop_factory=precise_event_loop) as runner:
            runner.run(emulate(args.rate, args.seed))
        return 0
    config = QUICK if args.quick else FULL
    if not args.quick:
        config = dataclasses.replace(config, hours=args.hours, rate=args.rate)
    config = dataclasses.replace(config, seed=args.seed, faults=not args.no_faults)
    report = asyncio.run(run_soak(config))
    print_report(report)
    return 0 if report.passed else 1


if __name__ == "__main__":
    sys.exit(main())
