"""The Sky Tracker driver's status check while its own presses change the status (issue #16).

``R``'s low nibble is the arrows pressed now and its flags the mode, so a press or release the
driver itself sends between two readings of a poll's agreement check (made for a garbling line)
changes the reply. Against the real emulator over a pty, with the wire's pacing: a press queued
while a status is read goes before the next reading (commands in turn, before polls), so the
presses land between the readings of a check every time."""

from __future__ import annotations

import asyncio
from pathlib import Path

from scopelink.drivers.skytracker import BadReplyError
from scopelink.mount import MountAxis, TrackingMode
from scopelink.protocol.skytracker import TrackerMode
from scopelink.servers.faults import Fault, FaultKind
from tests.support.skytracker_driver import rig

RATE_DEG_S = 10.0 / 3600.0
"""A GUIDE-mode arrow (10″/s): the motion barely moves the scope while the test runs."""

P, S = MountAxis.PRIMARY, MountAxis.SECONDARY
CYCLE = ((P, 1), (S, 1), (P, 0), (P, -1), (S, 0), (S, -1), (P, 0), (S, 0))
"""Eight presses and releases, each one ``move_axis``: eight different status bytes in turn (GUIDE
with r, r u, u, l u, l, l d, d pressed, then TRACK with none), so neither two readings of one
status check nor a reading and the status before it agree while the presses go on (in runs one
or two presses land between two readings; the cycle comes round only after eight)."""

POLLS = 12


async def test_a_status_poll_is_not_fooled_by_the_drivers_own_presses(tmp_path: Path) -> None:
    async with rig(tmp_path, "pty") as r:
        r.point(45.0, 90.0)
        await r.driver.set_tracking(TrackingMode.ALT_AZ)
        stop = asyncio.Event()
        presses = 0

        async def press_in_turn() -> None:
            nonlocal presses
            while not stop.is_set():
                axis, sign = CYCLE[presses % len(CYCLE)]
                await r.driver.move_axis(axis, sign * RATE_DEG_S)
                presses += 1

        async def poll(garble: bool) -> tuple[list[str], set[TrackerMode | None]]:
            """POLLS refreshes; with ``garble``, one ``R`` reply at a time garbled meanwhile
            (its top bit flipped: TRACK reads as UTILITY), whoever asked."""
            failures: list[str] = []
            modes: set[TrackerMode | None] = set()
            for _ in range(POLLS):
                if garble and not r.emulator.faults.faults:
                    r.emulator.faults.add(Fault(FaultKind.MALFORMED, "R"))
                for read in (r.driver.read_status, r.driver.refresh):  # a command; a poll
                    try:
                        await read()
                    except BadReplyError as error:
                        failures.append(str(error))
                modes.add(r.driver.tracker_mode)
            return failures, modes

        presser = asyncio.create_task(press_in_turn())
        try:
            before = presses
            failures, modes = await poll(garble=False)
            # A line that garbles still is not believed while the presses go on: a garbled
            # reading is read again, and the reading equal to what the driver pressed wins.
            garbled_failures, garbled_modes = await poll(garble=True)
        finally:
            stop.set()
            await presser
        pressed_meanwhile = presses - before
        for axis in MountAxis:
            await r.driver.move_axis(axis, 0.0)
        assert pressed_meanwhile >= POLLS, "the presses did not run between the polls"
        assert not failures, f"{len(failures)} of {2 * POLLS} reads failed: {failures[0]}"
        assert modes == {TrackerMode.GUIDE, TrackerMode.TRACK}  # the polls saw the presses
        assert len(r.emulator.faults.fired) >= POLLS // 2
        assert not garbled_failures, garbled_failures[0]
        assert garbled_modes <= {TrackerMode.GUIDE, TrackerMode.TRACK}  # no garbled mode believed
        assert r.emulator.tracker.remote_pressed == 0
        assert r.emulator.tracker.mode is TrackerMode.TRACK
