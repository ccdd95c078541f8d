"""SkyTrackerMount and the line's own rules: bus refusal during a GOTO and its back-off, the
calibration rule ("S only first after power-on"), and the strict (unbuffered, 8N2) PC port with
its control (unspaced sends fail clearly). Over a pty and TCP, against the real emulators.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from scopelink.drivers.skytracker import (
    BusOptions,
    BusRefusedError,
    CalibrationFactors,
    CalibrationRuleError,
    SkyTrackerMount,
)
from scopelink.links import Link, open_serial, open_tcp
from scopelink.mount import MountError, NotConnectedError
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.servers.skytracker.tracker import DEFAULT_CALIBRATION
from tests.support.skytracker_driver import (
    FAST,
    FAST_TIMEOUT_S,
    SITE,
    TRANSPORTS,
    assert_position_matches_sim,
    driver_position,
    rig,
    separation_deg,
    serve,
    sky_at,
    sky_tracker_mount,
)

transports = pytest.mark.parametrize("transport", TRANSPORTS)


# --- the bus during a GOTO ----------------------------------------------------------------------


@transports
async def test_bus_refused_during_goto_backs_off_then_fails_clearly(
    tmp_path: Path, transport: str
) -> None:
    async with rig(tmp_path, transport) as r:
        await r.driver.goto_equatorial(*sky_at(r.sim, 60.0, 200.0))
        started = time.monotonic()
        with pytest.raises(BusRefusedError, match="GOTO is running"):
            await r.driver.read_position()
        assert time.monotonic() - started >= sum(FAST.retry_delays_s)
        assert r.driver.line.statistics.bus_refusals == len(FAST.retry_delays_s) + 1
        # Polls meanwhile neither wait nor fail: the status says GOTO, the bus is not asked.
        refusals = r.driver.line.statistics.bus_refusals
        state = await r.driver.refresh()
        assert state.slewing
        assert r.driver.line.statistics.bus_refusals == refusals


@transports
async def test_bus_granted_once_the_goto_ends_during_the_back_off(
    tmp_path: Path, transport: str
) -> None:
    bus = BusOptions(retry_delays_s=(0.1, 0.2, 0.4, 0.8, 1.6))
    async with rig(tmp_path, transport, bus=bus, clock_rate=10.0) as r:
        here = r.point(40.0, 100.0)
        target = sky_at(r.sim, 40.0, 110.0)  # ~5 simulated seconds away, 0.5 s at 10x
        await r.driver.goto_equatorial(*target)
        position = await r.driver.read_position()
        assert r.driver.line.statistics.bus_refusals >= 1
        assert separation_deg(position, target) < 0.02
        assert separation_deg(position, here) > 5.0


# --- calibration --------------------------------------------------------------------------------


@transports
async def test_calibration_reads_any_time_but_writes_only_first(
    tmp_path: Path, transport: str
) -> None:
    async with rig(tmp_path, transport) as r:
        factory = await r.driver.read_calibration()
        assert factory.azimuth_factor == DEFAULT_CALIBRATION.azimuth_factor
        assert factory.ground_board_diameter_in == pytest.approx(20.0)
        assert factory.bearing_diameter_in == pytest.approx(8.0)
        sent = r.driver.line.statistics.commands_sent
        with pytest.raises(CalibrationRuleError, match="first command after it is switched on"):
            await r.driver.write_calibration(CalibrationFactors.for_telescope(24.0, 10.0))
        assert r.driver.line.statistics.commands_sent == sent  # refused before sending anything


@transports
async def test_calibration_written_first_after_power_on(tmp_path: Path, transport: str) -> None:
    wanted = CalibrationFactors.for_telescope(24.0, 10.0)
    async with rig(tmp_path, transport, connect=False) as r:
        await r.driver.write_calibration(wanted)  # connects, 'S' first
        assert r.driver.state.connected
        read = await r.driver.read_calibration()
        # The bias-128 float carries 24 significant bits.
        assert read.azimuth_factor == pytest.approx(wanted.azimuth_factor, rel=1e-7)
        assert read.elevation_factor == pytest.approx(wanted.elevation_factor, rel=1e-7)
        stored = r.emulator.tracker.calibration.calibration
        assert stored.azimuth_factor == read.azimuth_factor
        # A second connection to the same (not power-cycled) box: the box does not answer 'S'.
        await r.driver.disconnect()
        with pytest.raises(CalibrationRuleError, match="did not acknowledge"):
            await r.driver.write_calibration(CalibrationFactors.for_telescope(30.0, 12.0))
        with pytest.raises(NotConnectedError):  # the refused connection was not kept
            await r.driver.refresh()
    # Switched off and on (a new emulator on the same data): the factors were kept.
    async with rig(tmp_path, transport) as r:
        assert await r.driver.read_calibration() == read


# --- the strict, unbuffered PC port -----------------------------------------------------------


@transports
async def test_goto_and_sync_survive_the_strict_line(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport, strict_line=True) as r:
        target = sky_at(r.sim, 35.0, 60.0)
        await r.driver.goto_equatorial(*target)  # a 19-byte L99 line through the bus
        await r.driver.wait_for_goto(timeout_s=15.0)
        assert separation_deg(driver_position(r), target) < 0.02
        await r.driver.sync_equatorial(*target)
        await assert_position_matches_sim(r)
        if transport == "pty":  # two stop bits: the port never loses a byte
            assert r.driver.line.statistics.resyncs == 0
        # Over TCP the paced sends may bunch after an event-loop stall on a loaded machine (the
        # pacing catches up on its schedule); the retry inside the grant then recovers.


@transports
async def test_unspaced_sends_fail_on_the_strict_line(tmp_path: Path, transport: str) -> None:
    """The control: without two stop bits (pty) or pacing (TCP) the L99 line loses characters,
    and the driver says so instead of going somewhere else."""
    sim = sky_tracker_mount()
    async with SkyTrackerEmulator(sim, tmp_path, strict_line=True) as emulator:
        spec = await serve(emulator, transport)

        async def open_unspaced() -> Link:
            if transport == "pty":
                return await open_serial(spec, 9600, stopbits=1)
            host, port = spec.removeprefix("tcp://").split(":")
            return await open_tcp(host, int(port))

        driver = SkyTrackerMount(
            open_unspaced, site=SITE, clock=sim.clock.now, timeout_s=FAST_TIMEOUT_S, bus=FAST
        )

        async def connect_and_goto() -> None:
            await driver.connect()
            await driver.goto_equatorial(*sky_at(sim, 35.0, 60.0))

        try:
            with pytest.raises(MountError):  # DeviceError, or no Sky Commander found at all
                await connect_and_goto()
            assert emulator.tracker.mode.value == "U"  # no GOTO started
        finally:
            await driver.disconnect()


async def test_connect_after_a_synscan_probe_left_a_frame_open(tmp_path: Path) -> None:
    """A SynScan driver's echo probe ``K`` + one byte leaves the box waiting for the second
    payload byte of its own ``K``: the driver's first ``V`` is swallowed, the second answered."""
    async with rig(tmp_path, "pty", connect=False) as r:
        probe = await open_serial(r.spec, 9600, stopbits=2)
        await probe.write(b"Kx")
        await probe.close()
        await r.driver.connect()
        assert r.driver.identity.firmware == "v4.0"
        assert (
            r.driver.line.statistics.resyncs == 2
        )  # after the timeout, and past a late first answer
        assert r.emulator.tracker.guide_speeds_arcsec_s == (ord("x"), ord("V"))
