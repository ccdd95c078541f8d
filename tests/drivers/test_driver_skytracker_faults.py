"""SkyTrackerMount when the line misbehaves: every fault kind the emulator injects (the bus,
calibration and strict-line rules are in ``test_driver_skytracker_line.py``).

Each fault must end in a clear error or a transparent recovery, never in a wrong position: after
every fault the position the driver reports is compared with the simulator's. These run over a
pty; over TCP every command x every fault (and close + reopen) is in the fault matrix,
``test_fault_matrix_skytracker.py``.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

import pytest

from scopelink.drivers.skytracker import (
    BadReplyError,
    ReplyTimeoutError,
    SkyTrackerMount,
)
from scopelink.mount import DeviceError, MountError, NotConnectedError, TrackingMode
from scopelink.servers.faults import Fault, FaultKind
from tests.support.skytracker_driver import (
    assert_position_matches_sim,
    driver_position,
    rig,
    separation_deg,
)

transports = pytest.mark.parametrize("transport", ["pty"])
"""TCP: see the fault matrix."""


def tracking_of(driver: SkyTrackerMount) -> TrackingMode:
    """A function, so type checkers do not narrow the state between reads."""
    return driver.state.tracking


def fault(kind: FaultKind, command: str, seconds: float | None = None) -> Fault:
    return Fault(kind, command, seconds)


# --- replies lost, late, garbled ------------------------------------------------------------------


@transports
async def test_a_lost_status_reply_keeps_the_last_state(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        r.point(45.0, 90.0)
        await r.driver.refresh()
        before = r.driver.state
        r.emulator.faults.add(fault(FaultKind.DROP, "R"))
        with pytest.raises(ReplyTimeoutError, match="no reply to 'R: read status'"):
            await r.driver.refresh()
        kept = r.driver.state
        assert kept.ra_j2000_hours == before.ra_j2000_hours
        assert kept.dec_j2000_deg == before.dec_j2000_deg
        assert any("no reply to 'R" in problem for problem in kept.problems)
        assert r.driver.line.statistics.resyncs == 1
        await assert_position_matches_sim(r)  # recovered
        assert r.driver.state.problems == ()


@transports
@pytest.mark.parametrize(
    "bad",
    [
        fault(FaultKind.DROP, "Q"),
        fault(FaultKind.MALFORMED, "Q"),
        fault(FaultKind.SHORT, "Q"),
        fault(FaultKind.DELAY, "Q", 0.3),
    ],
    ids=str,
)
async def test_a_bad_bus_grant_is_retried_transparently(
    tmp_path: Path, transport: str, bad: Fault
) -> None:
    async with rig(tmp_path, transport) as r:
        r.point(30.0, 250.0)
        r.emulator.faults.add(bad)
        for _ in range(3):  # a late grant may spoil a few exchanges: never the position
            try:
                await assert_position_matches_sim(r)
            except DeviceError:
                assert r.driver.state.problems  # a clear error, the last position kept
        assert r.emulator.faults.fired
        assert r.driver.line.statistics.resyncs >= 1
        await assert_position_matches_sim(r)


@transports
async def test_a_slow_reply_still_arrives(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        r.emulator.faults.add(fault(FaultKind.SLOW, "V", 0.02))
        assert (await r.driver.read_status()) is not None
        assert r.driver.line.statistics.resyncs == 0


@transports
async def test_a_stalled_box_is_an_error_until_it_answers_again(
    tmp_path: Path, transport: str
) -> None:
    async with rig(tmp_path, transport) as r:
        r.emulator.faults.add(fault(FaultKind.STALL, "R"))
        for _ in range(2):
            with pytest.raises(ReplyTimeoutError):
                await r.driver.refresh()
        r.emulator.faults.resume()
        await assert_position_matches_sim(r)


@transports
async def test_a_halted_box_never_yields_a_wrong_position(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        r.point(50.0, 300.0)
        r.emulator.faults.add(fault(FaultKind.HALT, "R"))
        with pytest.raises(ReplyTimeoutError):
            await r.driver.refresh()
        r.emulator.faults.resume()  # the piled-up input is answered late
        good = 0
        for _ in range(6):
            before = r.sim_j2000()
            try:
                await r.driver.refresh()
            except DeviceError:
                continue
            read = driver_position(r)
            assert separation_deg(read, before) < 0.02
            good += 1
        assert good >= 3


@transports
async def test_a_closed_link_is_a_clear_error(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        r.emulator.faults.add(fault(FaultKind.CLOSE, "R"))
        with pytest.raises(MountError, match=r"link|no reply"):
            await r.driver.refresh()
        assert r.driver.state.problems
        assert not r.driver.state.connected  # a pty is gone for good (TCP reopens: the matrix)


@transports
@pytest.mark.parametrize(
    ("bad", "error"),
    [(FaultKind.DROP, ReplyTimeoutError), (FaultKind.MALFORMED, BadReplyError)],
)
async def test_no_identification_no_connection(
    tmp_path: Path, transport: str, bad: FaultKind, error: type[Exception]
) -> None:
    async with rig(tmp_path, transport, connect=False) as r:
        r.emulator.faults.add(Fault(bad, "V", times=None))  # every V (one is asked again)
        with pytest.raises(error, match="V: read version"):
            await r.driver.connect()
        assert not r.driver.state.connected
        with pytest.raises(NotConnectedError):
            await r.driver.refresh()


@transports
async def test_one_lost_version_reply_is_asked_again(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport, connect=False) as r:
        r.emulator.faults.add(fault(FaultKind.DROP, "V"))
        await r.driver.connect()
        assert r.driver.identity.firmware == "v4.0"
        assert (
            r.driver.line.statistics.resyncs == 2
        )  # after the timeout, and past a late first answer


@transports
async def test_a_garbled_status_byte_is_read_again_not_believed(
    tmp_path: Path, transport: str
) -> None:
    """A status byte has no redundancy: with its top bit flipped TRACK (0x00) reads as UTIL
    (0x80). A status other than the last one is read again, and believed only when two readings
    agree: one garbled reply misleads no poll (it used to, for one poll). The same garbling
    twice in a row would still be believed: the byte has no redundancy to tell."""
    async with rig(tmp_path, transport) as r:
        r.point(45.0, 90.0)
        await r.driver.set_tracking(TrackingMode.ALT_AZ)
        r.emulator.faults.add(fault(FaultKind.MALFORMED, "R"))
        await assert_position_matches_sim(r)
        assert r.emulator.faults.fired
        assert tracking_of(r.driver) is TrackingMode.ALT_AZ


async def test_a_sky_commander_silent_once_at_a_reconnection_is_read_again(
    tmp_path: Path,
) -> None:
    """Seen in bench.reconnect (2026-11-25): the link came back, the Sky Commander's first
    position replies after it were lost (stale bytes of the old connection in their way), and the
    driver concluded "no Sky Commander on the bus" for good: no position poll again, every
    position refused as stale while the link read as connected. A Sky Commander seen before
    is a fault to report and retry, not gone."""
    async with rig(tmp_path, "tcp") as r:
        r.point(40.0, 120.0)
        await assert_position_matches_sim(r)
        assert r.driver.commander_present is True
        await r.driver.line.link.close()  # the link is lost
        # The first position requests after it (the exchange, its retry, the catch-up): lost.
        r.emulator.commander_faults.add(Fault(FaultKind.DROP, "CR", times=3))
        for _ in range(3):  # reconnects, detects (the reply lost), then polls again
            with contextlib.suppress(MountError):  # the lost replies: a clear error
                await r.driver.refresh()
        assert r.emulator.commander_faults.fired
        await assert_position_matches_sim(r)
        r.driver.fresh_state()  # the position is served again
        assert r.driver.commander_present is True  # and known present again, for the next loss
