"""Commands that change what the SynScan emulator's mount does, each read back by another
process: stop after goto --no-wait, the configured horizon, move until Ctrl-C, tracking, sync."""

from __future__ import annotations

import asyncio
import signal
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.cli import (
    read_line_matching,
    scopelink,
    scopelink_here,
    separation_deg,
    settled_state,
    start_scopelink,
    state_of,
    synscan_emulator,
)


@pytest.fixture(scope="module")
def device() -> Iterator[str]:
    """A real-time emulated EQ6."""
    with synscan_emulator("--no-pacing") as spec:
        yield spec


def test_goto_no_wait_then_stop_from_another_command(config: Path, device: str) -> None:
    started = scopelink(config, "goto", "--altaz", "60", "90", "--no-wait", "--device", device)
    assert started.returncode == 0, started.stderr
    assert state_of(config, device)["slewing"] is True
    status, out, err = scopelink_here(config, "stop", "--device", device)
    assert status == 0, err
    assert out.startswith("stopped at")
    assert state_of(config, device)["slewing"] is False
    settled = settled_state(config, device)
    assert separation_deg(settled["alt_deg"], settled["az_deg"], 60.0, 90.0) > 5.0


def test_config_file_names_the_device_and_its_horizon_guards_it(
    tmp_path: Path, device: str
) -> None:
    config = tmp_path / "config.toml"
    config.write_text(f'device = "{device}"\n[horizon]\naltitude = 25\n', encoding="utf-8")
    before = settled_state(config)  # no --device: the file's
    refused = scopelink(config, "goto", "--altaz", "20", "100")
    assert refused.returncode == 1
    assert "below the configured horizon of 25.00°" in refused.stderr
    assert "[horizon]" in refused.stderr  # the hint says where the horizon is set
    after = state_of(config, device)
    assert after["slewing"] is False
    assert separation_deg(
        before["alt_deg"], before["az_deg"], after["alt_deg"], after["az_deg"]
    ) < (0.05)


def test_move_until_ctrl_c_then_the_axis_stays_stopped(config: Path, device: str) -> None:
    async def interrupt() -> tuple[int, str]:
        process = await start_scopelink(config, "move", "dec", "1", "--device", device)
        await read_line_matching(process.stdout, "until Ctrl-C", process.stderr)
        await asyncio.sleep(0.5)
        process.send_signal(signal.SIGINT)
        async with asyncio.timeout(20):
            out, _ = await process.communicate()
        return await process.wait(), out.decode()

    before = settled_state(config, device)
    status, out = asyncio.run(interrupt())
    assert status == 0, out
    assert "stopped at" in out
    after = settled_state(config, device)
    moved = separation_deg(before["alt_deg"], before["az_deg"], after["alt_deg"], after["az_deg"])
    assert moved > 0.2  # it turned while the command ran...
    time.sleep(0.5)
    later = state_of(config, device)
    assert separation_deg(after["alt_deg"], after["az_deg"], later["alt_deg"], later["az_deg"]) < (
        0.01
    )  # ...and stopped with it


def test_tracking_and_sync_persist_in_the_hand_control(config: Path, device: str) -> None:
    assert scopelink_here(config, "track", "on", "--device", device)[:2] == (
        0,
        "tracking: sidereal\n",
    )
    assert state_of(config, device)["tracking"] == "sidereal"  # a new connection reads it back
    assert scopelink_here(config, "track", "off", "--device", device)[:2] == (0, "tracking: off\n")
    assert state_of(config, device)["tracking"] == "off"
    here = settled_state(config, device)
    ra, dec = (here["ra_j2000_hours"] + 0.05) % 24, here["dec_j2000_deg"] - 0.5
    status, out, err = scopelink_here(config, "sync", f"{ra:.6f}", f"{dec:+.6f}", "-d", device)
    assert status == 0, err
    assert out.startswith("synced on RA")
    after = state_of(config, device)
    # Tracking is off, so RA drifts by a second of time per second until it is read.
    assert abs(((after["ra_j2000_hours"] - ra + 12) % 24) - 12) < 0.005
    assert after["dec_j2000_deg"] == pytest.approx(dec, abs=0.02)
