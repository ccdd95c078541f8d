"""Behaviour of real hand controls the emulator reproduces only when asked: the driver copes."""

from __future__ import annotations

import pytest

from scopelink.mount import MountAxis
from scopelink.protocol.synscan import (
    CancelGoto,
    GotoInProgress,
    IsGotoInProgress,
    Passthrough,
    PassthroughFailed,
    Version,
)
from scopelink.protocol.synscan import VersionDialect as Dialect
from scopelink.servers.faults import Fault, FaultKind
from scopelink.servers.synscan import Quirks, SynScanConfig
from tests.support.synscan_driver import TRANSPORTS, assert_position_matches, rig


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_swapped_model_reply_and_old_binary_version(transport: str) -> None:
    config = SynScanConfig(
        model=1,
        firmware=Version(3, 36, 2, Dialect.SYNSCAN_BINARY),
        quirks=Quirks(model_swapped=True),
    )
    async with rig(transport, config=config) as r:
        assert r.mount.identity.model == "HEQ5 GOTO"
        assert r.mount.identity.firmware == "03.36.02"
        assert r.mount.info is not None
        assert r.mount.info.old_firmware
        assert r.mount.info.model.swapped
        assert 1 in r.mount.wire.avoid_echo
        assert_position_matches(await r.mount.refresh(), r.sim.snapshot())


async def test_a_reply_after_4_5_s_is_within_the_default_5_s_timeout() -> None:
    async with rig("tcp") as r:
        assert r.mount.timeout_s == 5.0
        r.emulator.faults.add(Fault(FaultKind.DELAY, "e", seconds=4.5))
        resyncs = r.mount.wire.statistics.resyncs
        assert_position_matches(await r.mount.refresh(), r.sim.snapshot())
        assert r.emulator.faults.fired
        assert r.mount.wire.statistics.resyncs == resyncs  # answered, not recovered


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_a_sticky_goto_flag_after_an_altaz_goto_ends_when_the_position_settles(
    transport: str,
) -> None:
    config = SynScanConfig(quirks=Quirks(sticky_altaz_goto=True))
    async with rig(transport, config=config) as r:
        await r.mount.goto_horizontal(45.0, 120.0)
        # Standing still far from the target (the stepped clock has not moved): still slewing.
        for _ in range(4):
            assert (await r.mount.refresh()).slewing
        r.sim.step(120.0)
        readings = [await r.mount.refresh() for _ in range(3)]
        assert [state.slewing for state in readings] == [True, True, False]
        assert (readings[-1].alt_deg, readings[-1].az_deg) == pytest.approx((45.0, 120.0), abs=1e-4)
        # The hand control still says a goto is running: the driver judged by the position.
        assert await r.mount.wire.ask(IsGotoInProgress()) == GotoInProgress(True)
        assert not (await r.mount.refresh()).slewing

        # Stopped short of the target (as by a limit): settled once the timeout has passed.
        r.mount.altaz_settle_timeout_s = 0.0
        await r.mount.goto_horizontal(30.0, 200.0)
        readings = [await r.mount.refresh() for _ in range(3)]
        assert [state.slewing for state in readings] == [True, True, False]


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_abort_stops_axes_that_old_firmware_restarts_after_cancel(transport: str) -> None:
    config = SynScanConfig(quirks=Quirks(resume_after_cancel=True))
    async with rig(transport, config=config) as r:
        # The quirk is real: a bare M lets the axis run on.
        await r.mount.move_axis(MountAxis.SECONDARY, -2.0)
        await r.mount.wire.ask(CancelGoto())
        r.sim.step(5.0)
        first = r.sim.snapshot()
        r.sim.step(5.0)
        assert r.sim.snapshot().alt_deg != pytest.approx(first.alt_deg, abs=1.0)

        # The driver's abort also stops both axes at rate 0.
        await r.mount.abort()
        r.sim.step(5.0)
        stopped = await r.mount.refresh()
        assert not stopped.slewing
        r.sim.step(30.0)
        still = await r.mount.refresh()
        # Equal to the precision of e (24 bits: 2e-5°); the axis ran at 2°/s before.
        assert (still.alt_deg, still.az_deg) == pytest.approx(
            (stopped.alt_deg, stopped.az_deg), abs=1e-4
        )
        assert_position_matches(still, r.sim.snapshot())


async def test_a_failed_passthrough_with_its_extra_byte_keeps_the_stream_in_step() -> None:
    async with rig("tcp") as r:
        resyncs = r.mount.wire.statistics.resyncs
        # A motor controller address nobody answers: 3 requested bytes, one extra byte, '#'.
        reply = await r.mount.wire.ask(Passthrough(bytes((1, 0x20, 5, 0, 0, 0, 3))))
        assert isinstance(reply, PassthroughFailed)
        assert reply.data == bytes(3)
        assert_position_matches(await r.mount.refresh(), r.sim.snapshot())
        assert r.mount.wire.statistics.resyncs == resyncs
