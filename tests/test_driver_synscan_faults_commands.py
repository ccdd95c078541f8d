"""Faults on the replies to commands (goto, rate, sync): the command is re-sent after
resynchronising (every SynScan command is idempotent) and the mount ends where it should.

Every feature runs over both transports in test_driver_synscan.py; here one transport per case
keeps the file fast. The timeout is 2 s, not 0.5 s: the simulated mount plans a goto or sync in
0.5-0.8 s of CPU, and a timeout shorter than the device's honest answer time would test nothing
but the machine."""

from __future__ import annotations

import pytest

from scopelink.mount import MountAxis
from scopelink.servers.faults import Fault, FaultKind
from tests.test_driver_synscan_support import assert_position_matches, rig

TIMEOUT_S = 2.0


async def test_malformed_acknowledgements_of_commands_are_recovered() -> None:
    async with rig("tcp", timeout_s=TIMEOUT_S) as r:
        r.emulator.faults.add(Fault(FaultKind.MALFORMED, "r"))
        await r.mount.goto_equatorial(7.5, 35.0)  # re-sent after resynchronising: same target
        r.sim.step(120.0)
        state = await r.mount.refresh()
        assert not state.slewing
        assert state.ra_j2000_hours == pytest.approx(7.5, abs=1e-5)
        assert_position_matches(state, r.sim.snapshot())

        r.emulator.faults.add(Fault(FaultKind.MALFORMED, "P"))
        await r.mount.move_axis(MountAxis.SECONDARY, 1.0)
        r.sim.step(2.0)
        await r.mount.move_axis(MountAxis.SECONDARY, 0.0)
        r.sim.step(3.0)
        assert_position_matches(await r.mount.refresh(), r.sim.snapshot())

        r.emulator.faults.add(Fault(FaultKind.MALFORMED, "s"))
        await r.mount.sync_equatorial(7.52, 35.1)
        assert_position_matches(await r.mount.refresh(), r.sim.snapshot())
        assert r.mount.state.ra_j2000_hours == pytest.approx(7.52, abs=1e-5)
        assert len(r.emulator.faults.fired) == 3
        # One failed exchange per fault (resyncs may be more: a poll cancelled when the horizon
        # guard's poller stops resynchronises too).
        assert r.mount.wire.statistics.failures == 3


@pytest.mark.parametrize(("transport", "kind"), [("pty", FaultKind.DROP), ("tcp", FaultKind.SHORT)])
async def test_a_lost_goto_acknowledgement_is_recovered(transport: str, kind: FaultKind) -> None:
    async with rig(transport, timeout_s=TIMEOUT_S) as r:
        r.emulator.faults.add(Fault(kind, "r"))
        await r.mount.goto_equatorial(7.5, 35.0)
        r.sim.step(120.0)
        state = await r.mount.refresh()
        assert state.ra_j2000_hours == pytest.approx(7.5, abs=1e-5)
        assert_position_matches(state, r.sim.snapshot())
