"""Every fault the emulator injects ends in a transparent recovery or a clear error, and the driver
never reports a position the simulator does not have (real pty and TCP, 0.5 s timeout).

Each case runs over one transport (alternating): every feature runs over both in
test_driver_synscan.py, and the recovery code does not depend on the transport."""

from __future__ import annotations

import asyncio

import pytest

from scopelink.drivers.synscan.polling import FULL_READ_EVERY
from scopelink.mount import DeviceError
from scopelink.servers.faults import Fault, FaultInjector, FaultKind
from tests.support.synscan_driver import TRANSPORTS, Rig, assert_position_matches, rig

TIMEOUT_S = 0.5


async def assert_reads_the_truth(r: Rig) -> None:
    assert_position_matches(await r.mount.refresh(), r.sim.snapshot())


def fired(r: Rig, kind: FaultKind) -> bool:
    return any(record.fault.kind is kind for record in r.emulator.faults.fired)


@pytest.mark.parametrize(
    ("transport", "fault"),
    [
        ("pty", Fault(FaultKind.DROP, "e")),
        ("tcp", Fault(FaultKind.SHORT, "e")),
        ("pty", Fault(FaultKind.MALFORMED, "e")),
        ("tcp", Fault(FaultKind.DELAY, "e", seconds=0.8)),  # beyond the timeout: reply discarded
        ("pty", Fault(FaultKind.SLOW, "e", seconds=0.01)),  # slow but within the timeout
        ("tcp", Fault(FaultKind.SLOW, "e", seconds=0.04)),  # 0.7 s: drained, then recovered
        ("tcp", Fault(FaultKind.DROP, "L")),
        ("pty", Fault(FaultKind.MALFORMED, "t")),
        ("tcp", Fault(FaultKind.SHORT, "p")),
    ],
    ids=str,
)
async def test_a_bad_reply_to_a_poll_is_recovered_transparently(
    transport: str, fault: Fault
) -> None:
    async with rig(transport, timeout_s=TIMEOUT_S) as r:
        before = r.mount.wire.statistics.resyncs
        r.emulator.faults.add(fault)
        # 't' and 'p' are read every FULL_READ_EVERY cycles of a mount at rest.
        for _ in range(FULL_READ_EVERY):
            await assert_reads_the_truth(r)
            if fired(r, fault.kind):
                break
        assert fired(r, fault.kind)
        recovered = fault.kind is not FaultKind.SLOW or (fault.seconds or 0) * 18 > TIMEOUT_S
        assert r.mount.wire.statistics.resyncs == before + int(recovered)
        assert not r.mount.state.problems
        await assert_reads_the_truth(r)


async def test_a_reply_too_slow_for_the_timeout_is_an_error_then_recovered() -> None:
    async with rig("pty", timeout_s=0.3) as r:
        good = r.mount.state
        # 18 bytes take 1.7 s: longer than the resynchronising echo's patience (one timeout
        # after each stale byte, three at most), so the device counts as not answering.
        r.emulator.faults.add(Fault(FaultKind.SLOW, "e", seconds=0.1))
        with pytest.raises(DeviceError, match=r"no reply to 'get precise RA/Dec' within 0\.3 s"):
            await r.mount.refresh()
        # The last good coordinates are kept, and the problem is named.
        assert r.mount.state.ra_j2000_hours == good.ra_j2000_hours
        assert r.mount.state.problems
        assert "within 0.3 s" in r.mount.state.problems[0]
        await asyncio.sleep(1.0)  # the slow reply is over
        await assert_reads_the_truth(r)
        assert not r.mount.state.problems


@pytest.mark.parametrize(("transport", "kind"), [("pty", FaultKind.STALL), ("tcp", FaultKind.HALT)])
async def test_a_hung_device_is_a_clear_error_until_it_answers_again(
    transport: str, kind: FaultKind
) -> None:
    async with rig(transport, timeout_s=TIMEOUT_S) as r:
        r.emulator.faults.add(Fault(kind, "e"))
        with pytest.raises(DeviceError, match="resynchronising failed") as raised:
            await r.mount.refresh()
        assert "is the hand control switched on" in str(raised.value)
        with pytest.raises(DeviceError, match="not sent"):
            await r.mount.abort()  # still hung: the next command resynchronises first
        r.emulator.faults.resume()
        await assert_reads_the_truth(r)
        assert not r.mount.state.problems


async def test_a_closed_tcp_connection_is_reopened_transparently() -> None:
    async with rig("tcp", timeout_s=TIMEOUT_S) as r:
        r.emulator.faults.add(Fault(FaultKind.CLOSE, "e"))
        await assert_reads_the_truth(r)
        assert fired(r, FaultKind.CLOSE)
        assert r.mount.wire.statistics.reconnects == 2  # connect, then after the close


async def test_a_closed_pty_is_a_clear_error() -> None:
    async with rig("pty", timeout_s=TIMEOUT_S) as r:
        good = r.mount.state
        r.emulator.faults.add(Fault(FaultKind.CLOSE, "e"))
        with pytest.raises(DeviceError, match=r"closed|cannot open"):
            await r.mount.refresh()
        assert r.mount.state.ra_j2000_hours == good.ra_j2000_hours
        assert r.mount.state.problems


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_connect_survives_a_lost_echo(transport: str) -> None:
    faults = FaultInjector([Fault(FaultKind.DROP, "K")])
    async with rig(transport, timeout_s=TIMEOUT_S, faults=faults) as r:
        assert r.mount.state.connected
        assert fired(r, FaultKind.DROP)
        await assert_reads_the_truth(r)


async def test_random_faults_on_every_command_never_give_a_wrong_position() -> None:
    faults = FaultInjector(seed=4)
    async with rig("tcp", timeout_s=0.3, faults=faults) as r:
        for kind in (FaultKind.DROP, FaultKind.SHORT, FaultKind.MALFORMED):
            faults.add(Fault(kind, "any", probability=0.05))
        errors = 0
        for _ in range(40):
            try:
                state = await r.mount.refresh()
            except DeviceError:
                errors += 1
                continue
            assert_position_matches(state, r.sim.snapshot())
        assert len(faults.fired) >= 3
        assert errors <= 3  # two faults in a row are rare; one is always recovered


async def test_a_silent_device_fails_connect_and_the_link_is_closed() -> None:
    """Nothing answers the opening echo: connect raises DeviceError and hangs up (no leaked
    link keeping the port busy for the next attempt, e.g. autodetection's Sky Tracker try)."""
    import asyncio as _asyncio

    from scopelink.astro import Site
    from scopelink.drivers.synscan import SynScanMount
    from scopelink.mount import DeviceError

    hung_up = _asyncio.Event()

    async def silent(reader: _asyncio.StreamReader, writer: _asyncio.StreamWriter) -> None:
        while await reader.read(100):
            pass  # swallow the echoes, answer nothing
        hung_up.set()
        writer.close()

    server = await _asyncio.start_server(silent, "127.0.0.1", 0)
    port = server.sockets[0].getsockname()[1]
    async with server:
        mount = SynScanMount(f"tcp://127.0.0.1:{port}", site=Site(45.0, 7.0), timeout_s=0.3)
        with pytest.raises(DeviceError):
            await mount.connect()
        await _asyncio.wait_for(hung_up.wait(), 5)
        assert not mount.state.connected
