"""The Sky Commander's object store survives a restart and a ``kill -9`` in the middle of writes."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import sys
from pathlib import Path

from scopelink.links import open_tcp
from scopelink.protocol.skytracker import Acknowledge, LoadObject, PositionReply, ReadPosition
from scopelink.servers.skytracker import ObjectStore, SkyCommanderEmulator, StoredObject
from tests.support.skytracker_emulator import CommanderSession, sky_tracker_mount


async def test_stored_objects_survive_a_restart(tmp_path: Path) -> None:
    async with SkyCommanderEmulator(sky_tracker_mount(), tmp_path) as emulator:
        host, port = await emulator.on_tcp()
        async with await open_tcp(host, port) as link:
            session = CommanderSession(link)
            assert (await session.send(LoadObject(7, 1.5, -20.25))) == Acknowledge()
            assert (await session.send(LoadObject(58, 23.999, 89.5))) == Acknowledge()
            assert isinstance(await session.send(ReadPosition()), PositionReply)
        assert emulator.commander.current_object is None  # L00-L58 do not make it current
    store = ObjectStore(tmp_path)
    assert store.get(7) == StoredObject(1.5, -20.25)
    assert store.get(58) == StoredObject(23.999, 89.5)
    assert store.get(0) is None


async def test_kill_9_during_writes_leaves_a_whole_store(tmp_path: Path) -> None:
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "scopelink",
        "emulate",
        "skycommander",
        "--tcp",
        "127.0.0.1:0",
        "--data-dir",
        str(tmp_path),
        stdout=asyncio.subprocess.PIPE,
    )
    assert process.stdout is not None
    async with asyncio.timeout(20):
        address = (await process.stdout.readline()).decode().split()[-1]
    host, port = address.rsplit(":", 1)
    acknowledged = 0
    async with await open_tcp(host, int(port)) as link:
        session = CommanderSession(link)
        for number in range(40):
            slot = number % 59
            reply = await session.send(LoadObject(slot, number * 0.5 % 24, number - 20.0))
            assert reply == Acknowledge()
            acknowledged += 1
        # Unacknowledged writes in flight while the process dies.
        for number in range(40, 59):
            await link.write(LoadObject(number, 1.0, 1.0).encode())
        os.kill(process.pid, signal.SIGKILL)
        await process.wait()
    document = json.loads((tmp_path / "skycommander-objects.json").read_bytes())
    store = ObjectStore(tmp_path)
    assert len(document["slots"]) >= acknowledged
    for number in range(acknowledged):
        assert store.get(number) == StoredObject(number * 0.5 % 24, number - 20.0)
