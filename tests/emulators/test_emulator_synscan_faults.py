"""Injected faults are observable on the wire; clients' own patterns are answered correctly."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime

import pytest

from scopelink.astro import Site
from scopelink.links import Link, LinkClosedError, open_tcp
from scopelink.servers.faults import Fault, FaultInjector, FaultKind, FaultSpecError, corrupt
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(40.4, 3.7)


@asynccontextmanager
async def emulator(
    faults: FaultInjector | None = None, config: SynScanConfig | None = None
) -> AsyncIterator[tuple[SynScanEmulator, Link]]:
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped(datetime(2026, 3, 1, tzinfo=UTC)))
    async with SynScanEmulator(mount, config, faults=faults, wire=None) as device:
        link = await open_tcp(*await device.on_tcp())
        async with link:
            yield device, link


async def reply(link: Link, count: int, seconds: float = 1.0) -> bytes:
    async with asyncio.timeout(seconds):
        return await link.read_exactly(count)


async def silent(link: Link, seconds: float = 0.3) -> bool:
    try:
        async with asyncio.timeout(seconds):
            await link.read()
    except TimeoutError:
        return True
    return False


def test_fault_syntax() -> None:
    assert Fault.parse("e:drop:once") == Fault(FaultKind.DROP, "e")
    assert Fault.parse("any:delay=6:p=0.1") == Fault(FaultKind.DELAY, "any", 6.0, None, 0.1)
    assert Fault.parse("K:slow=0.2:times=3") == Fault(FaultKind.SLOW, "K", 0.2, 3)
    assert Fault.parse(str(Fault(FaultKind.CLOSE, "V", times=None))).times is None
    for bad in ("e", "e:explode", "e:drop:p=2", "e:drop:times=0", "e:delay=x"):
        with pytest.raises(FaultSpecError):
            Fault.parse(bad)


def test_probabilistic_faults_repeat_with_a_seed() -> None:
    def draws(seed: int) -> list[bool]:
        injector = FaultInjector([Fault.parse("any:drop:p=0.5")], seed=seed)
        return [injector.select("e") is not None for _ in range(40)]

    assert draws(7) == draws(7)
    assert 5 < sum(draws(7)) < 35


async def test_drop_short_malformed_slow_delay() -> None:
    faults = FaultInjector()
    async with emulator(faults) as (_, link):
        faults.add(Fault(FaultKind.DROP, "K"))
        await link.write(b"Ka")
        assert await silent(link)
        await link.write(b"Kb")
        assert await reply(link, 2) == b"b#"

        faults.add(Fault(FaultKind.SHORT, "e"))
        await link.write(b"e")
        assert await reply(link, 17)
        assert await silent(link)

        faults.add(Fault(FaultKind.MALFORMED, "V"))
        await link.write(b"V")
        assert await reply(link, 7) == corrupt(b"042705#")

        faults.add(Fault(FaultKind.SLOW, "K", 0.05))
        loop = asyncio.get_running_loop()
        started = loop.time()
        await link.write(b"Kc")
        assert await reply(link, 2) == b"c#"
        assert loop.time() - started >= 0.05

        faults.add(Fault(FaultKind.DELAY, "J", 0.4))
        await link.write(b"J")
        assert await silent(link, 0.2)
        assert await reply(link, 2) == b"\x01#"
        assert [fired.fault.kind for fired in faults.fired] == [
            FaultKind.DROP,
            FaultKind.SHORT,
            FaultKind.MALFORMED,
            FaultKind.SLOW,
            FaultKind.DELAY,
        ]


async def test_stall_halt_and_close() -> None:
    faults = FaultInjector()
    async with emulator(faults) as (_, link):
        faults.add(Fault(FaultKind.STALL, "K"))
        await link.write(b"Ka")
        await link.write(b"J")
        assert await silent(link)
        faults.resume()
        await link.write(b"Kb")
        assert await reply(link, 2) == b"b#"

        faults.add(Fault(FaultKind.HALT))
        await link.write(b"Kc")
        await link.write(b"Kd")
        assert await silent(link)
        faults.resume()
        assert await reply(link, 2) == b"d#"  # read after the halt, in order

        faults.add(Fault(FaultKind.CLOSE, "V"))
        await link.write(b"V")
        with pytest.raises(LinkClosedError):
            await reply(link, 1)


async def test_stellarium_polls_e_without_handshake() -> None:
    async with emulator() as (_, link):
        replies = []
        for _ in range(3):
            await link.write(b"e")
            replies.append(await reply(link, 18))
            await asyncio.sleep(0.05)
        for data in replies:
            assert data[8:9] == b","
            assert data[-1:] == b"#"
            assert set(data[:8] + data[9:17]) <= set(b"0123456789ABCDEF")
            assert data[6:8] == b"00"
            assert data[15:17] == b"00"


async def test_skysafari_version_with_a_stray_hash_and_back_to_back_commands() -> None:
    async with emulator() as (_, link):
        await link.write(b"V#")
        assert await reply(link, 7) == b"042705#"
        assert await silent(link, 0.2)
        await link.write(b"T\x00MM")  # INDI's abort, written without waiting
        assert await reply(link, 3) == b"###"


async def test_latency_delays_every_reply() -> None:
    async with emulator(config=SynScanConfig(latency_s=0.3)) as (_, link):
        await link.write(b"Kx")
        assert await silent(link, 0.15)
        assert await reply(link, 2) == b"x#"
