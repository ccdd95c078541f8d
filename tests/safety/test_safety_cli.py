"""``scopelink goto`` and ``scopelink move`` as a user runs them (subprocesses), with the horizon
from the settings file, against the SynScan emulator (device horizon -10°) in this process."""

from __future__ import annotations

import asyncio
from pathlib import Path

from tests.support.cli import start_scopelink
from tests.support.safety import (
    HORIZON_DEG,
    TOLERANCE_DEG,
    Rig,
    synscan_rig,
    wait_until_still,
)


def settings(tmp_path: Path, rig: Rig) -> Path:
    """The user's settings: the emulator's port, the test site, a 10° horizon."""
    assert rig.mount.identity.link.startswith("tcp://")
    config = tmp_path / "config.toml"
    config.write_text(
        f'device = "{rig.mount.identity.link}"\n'
        "[site]\nlatitude = 48.0\nlongitude = 11.0\npressure = 0\n"
        f"[horizon]\naltitude = {HORIZON_DEG}\n",
        encoding="utf-8",
    )
    return config


async def run(config: Path, *args: str) -> tuple[int, str, str]:
    process = await start_scopelink(config, *args)
    async with asyncio.timeout(60):
        out, err = await process.communicate()
    assert process.returncode is not None
    return process.returncode, out.decode(), err.decode()


async def test_cli_gotos_below_the_horizon_never_reach_the_device(tmp_path: Path) -> None:
    async with synscan_rig(real_time=True) as rig:
        config = settings(tmp_path, rig)
        status, _, err = await run(config, "goto", "--altaz", "2", "200", "--no-wait")
        assert status == 1, err
        assert "below the configured horizon of 10.00°" in err
        assert "[horizon]" in err  # the hint names where the horizon is set
        assert rig.gotos_received() == []


async def test_cli_move_is_stopped_above_the_horizon(tmp_path: Path) -> None:
    async with synscan_rig(at=(12.5, 250.0), real_time=True) as rig:
        config = settings(tmp_path, rig)
        status, out, err = await run(config, "move", "ra", "3", "--for", "1")
        assert status == 0, err
        assert "stopped at" in out
        assert "below the configured horizon" in err  # the guard's warning names the cause
        await wait_until_still(rig)
        assert rig.slews_received()
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg
