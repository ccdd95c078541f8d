"""The stack under test, each part in its own process: the SynScan emulator (the ``--emulator``
role, its faults switched from the bench on stdin) and ``scopelink serve`` on it."""

from __future__ import annotations

import asyncio
import logging
import re
import signal
import sys
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from bench.processes import environment, start_scopelink, stop
from bench.soak import device_sky
from bench.soak.config import SITE, SoakConfig
from bench.soak.night import Night
from scopelink.servers.faults import Fault, FaultInjector
from scopelink.servers.hosting import SERIAL_9600_8N1
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

# --- the device: a SynScan emulator in its own process, its faults switched from here -----------

ROOT = Path(__file__).resolve().parents[2]
"""The repository: the emulator process runs ``python -m bench.soak`` from there."""


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
    ``resume`` (end a stall or halt), ``count`` (prints ``commands N``), ``meridian`` (prints the
    tube's worst standing against its meridian limit in the device's own sky,
    :mod:`bench.soak.device_sky`). Fired faults are logged as ``scopelink emulate`` logs them."""
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(name)s %(message)s")
    logging.getLogger("scopelink.servers.faults").setLevel(logging.INFO)
    faults = CountingInjector(seed=seed)
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock(rate=rate))
    config = SynScanConfig(model=EQ6.synscan_model_code or 0)
    loop = asyncio.get_running_loop()
    stdin = asyncio.StreamReader()
    await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(stdin), sys.stdin)
    meridian = device_sky.DeviceMeridian()
    watcher = asyncio.create_task(device_sky.watch(mount, meridian))
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
                case "meridian":
                    print(meridian.line(), flush=True)
    watcher.cancel()


class Emulator:
    """The bench's end of the ``--emulator`` process."""

    def __init__(self, process: asyncio.subprocess.Process) -> None:
        self.process = process

    async def say(self, line: str) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write(f"{line}\n".encode())
        await self.process.stdin.drain()

    async def commands(self) -> int:
        return int((await self._ask("count")).split()[1])

    async def meridian(self) -> tuple[int, float, str]:
        """(samples, worst excess in degrees, where): see :mod:`bench.soak.device_sky`."""
        return device_sky.parse(await self._ask("meridian"))

    async def _ask(self, line: str) -> str:
        await self.say(line)
        assert self.process.stdout is not None
        async with asyncio.timeout(5):
            return (await self.process.stdout.readline()).decode()


async def start_emulator(config: SoakConfig, home: Path) -> tuple[Emulator, int]:
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
    printed = await read_until(process, lambda line: "listening on" in line)
    found = re.search(r"127\.0\.0\.1:(\d+)", printed)
    assert found is not None
    return Emulator(process), int(found.group(1))


MERIDIAN_STOP = "past the meridian on the"
"""In serve's notice of a meridian stop ("tracking was stopped N° past the meridian on the west
side of the pier: ..."), judged on serve's clock: see :mod:`bench.soak.device_sky`."""

# --- the processes -------------------------------------------------------------------------------


async def read_until(process: asyncio.subprocess.Process, last: Callable[[str], bool]) -> str:
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


async def watch_emulator_log(process: asyncio.subprocess.Process, night: Night) -> None:
    """The emulator logs every fault that fires, stamped with its wall clock."""
    assert process.stderr is not None
    while line := (await process.stderr.readline()).decode(errors="replace"):
        if found := _FIRES.search(line.rstrip()):
            # logging's asctime: local time to the millisecond
            stamp = datetime.strptime(found.group(1), "%Y-%m-%d %H:%M:%S,%f").astimezone(UTC)
            night.fault_stamps.append((stamp, found.group(2) + (found.group(3) or "")))


async def watch_serve_log(process: asyncio.subprocess.Process, night: Night) -> None:
    assert process.stderr is not None
    while line := (await process.stderr.readline()).decode(errors="replace"):
        night.serve_log.append(f"{night.now():7.1f} s {line.rstrip()}")
        if "was stopped at" in line:
            night.guard_stops.append(night.now())
        if MERIDIAN_STOP in line:
            night.meridian_stops.append(night.now())


def listening_port(printed: str, label: str) -> int:
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


async def start_serve(home: Path, device_port: int) -> tuple[asyncio.subprocess.Process, str]:
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
        return serve, await read_until(serve, lambda line: line == "Ctrl-C stops.")
    except BaseException:
        await stop(serve)
        raise
