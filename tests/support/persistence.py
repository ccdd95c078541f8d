"""Writers that ``kill -9`` tests run in real child processes, and the harness that kills them.

Each writer loops doing real persistent writes through a public front end (the ``scopelink``
command line, the Alpaca server's start, the Sky Commander's serial protocol over TCP) and
appends an acknowledgement line to a file after each write *returns*: a write acknowledged before
the SIGKILL must be on disk.

Children are forked by a "zygote" (``python -m tests.support.persistence``: a
single-threaded process that has imported scopelink already), so a kill round costs a few
milliseconds instead of a 1-second interpreter start; that is what lets a test kill each writer
dozens of times in a few seconds. The zygote also does the killing, at the requested delay after
the fork, and reaps the child before it answers: when :meth:`Zygote.run_and_kill` returns, the
writer is gone and what is on disk is final.
"""

from __future__ import annotations

import asyncio
import itertools
import json
import os
import random
import signal
import subprocess
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from scopelink.protocol.skytracker import Acknowledge, LoadObject
from scopelink.servers.skytracker import StoredObject

Acknowledger = Callable[[str], None]
"""How a writer reports that a write has returned."""

_CHILD_DEADLINE_S = 20.0
"""A child nobody kills stops by itself (a test that failed half-way leaves no orphans)."""
_REPOSITORY = Path(__file__).resolve().parents[2]


@dataclass(frozen=True, slots=True)
class KillRound:
    """One child killed: what it acknowledged (in order) and whether the SIGKILL found it alive."""

    acknowledged: list[str]
    killed_while_running: bool


class Zygote:
    """The forking process (see the module docstring); one per test module."""

    def __init__(self) -> None:
        self._process = subprocess.Popen(
            [sys.executable, "-m", "tests.support.persistence"],
            cwd=_REPOSITORY,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self._answer() == {"ready": True}

    def _answer(self) -> dict[str, Any]:
        assert self._process.stdout is not None
        line = self._process.stdout.readline()
        assert line, "the zygote died (see its stderr)"
        answer: dict[str, Any] = json.loads(line)
        return answer

    def run_and_kill(
        self, writer: str, arguments: list[Any], delay_s: float, acks: Path
    ) -> KillRound:
        """Fork ``writer(*arguments, acknowledge)``, SIGKILL it after ``delay_s``, reap it."""
        assert self._process.stdin is not None
        request = {"writer": writer, "arguments": arguments, "delay": delay_s, "acks": str(acks)}
        self._process.stdin.write(json.dumps(request) + "\n")
        self._process.stdin.flush()
        answer = self._answer()
        text = acks.read_text(encoding="utf-8")
        # Only whole lines count: a line the kill cut short was never acknowledged.
        return KillRound(text.split("\n")[:-1], bool(answer["killed"]))

    def close(self) -> None:
        assert self._process.stdin is not None
        self._process.stdin.close()
        self._process.wait(timeout=10)


def delays(seed: int, count: int, low_s: float, high_s: float) -> list[float]:
    """Seeded random kill delays, so a failure can be replayed."""
    generator = random.Random(seed)
    return [generator.uniform(low_s, high_s) for _ in range(count)]


def _stop_after_deadline() -> float:
    return time.monotonic() + _CHILD_DEADLINE_S


# --- the writers (run in the children) ------------------------------------------------------------


def devices_for(number: int) -> str:
    """The device ``config set`` writes together with elevation ``number`` (alternates)."""
    return "sim" if number % 2 == 0 else "sim:az-gti"


def config_writer(config: str, first: int, acknowledge: Acknowledger) -> None:
    """``scopelink config set site.elevation N device D`` for N = first, first+1, ..."""
    from scopelink.cli.main import main

    os.environ["SCOPELINK_CONFIG"] = config
    stop = _stop_after_deadline()
    for number in itertools.count(first):
        status = main(
            ["config", "set", "site.elevation", str(number), "device", devices_for(number)]
        )
        if status != 0:
            acknowledge(f"error {status}")
            return
        acknowledge(str(number))
        if time.monotonic() > stop:
            return


def unique_id_server(state_dir: str, acknowledge: Acknowledger) -> None:
    """Start an Alpaca server in ``state_dir`` and acknowledge its UniqueID once it serves."""
    from scopelink.astro import Site
    from scopelink.servers.alpaca import AlpacaServer
    from scopelink.sim import SimulatedMount

    async def serve() -> None:
        mount = SimulatedMount(site=Site(51.5, 0.0))
        server = AlpacaServer(mount, port=0, discovery_port=None, state_dir=Path(state_dir))
        async with server:
            acknowledge(server.unique_id)
            await asyncio.sleep(_CHILD_DEADLINE_S)

    asyncio.run(serve())


def stored_object_for(number: int) -> StoredObject:
    """What write ``number`` puts in slot ``number % 59``: distinct for every number < 8160 and
    exact through the protocol's encoding."""
    return StoredObject((number % 48) * 0.5, float((number // 48) % 170 - 85))


def commander_writer(data_dir: str, first: int, acknowledge: Acknowledger) -> None:
    """Store objects ``first``, ``first+1``, ... through a Sky Commander emulator's serial protocol
    (over TCP) and acknowledge each once the device has acknowledged it."""
    from scopelink.links import open_tcp
    from scopelink.servers.skytracker import SkyCommanderEmulator
    from tests.support.skytracker_emulator import CommanderSession, sky_tracker_mount

    async def store() -> None:
        emulator = SkyCommanderEmulator(sky_tracker_mount(), Path(data_dir), pace=False)
        async with emulator:
            host, port = await emulator.on_tcp()
            async with await open_tcp(host, port) as link:
                session = CommanderSession(link)
                stop = _stop_after_deadline()
                for number in itertools.count(first):
                    item = stored_object_for(number)
                    command = LoadObject(number % 59, item.ra_hours, item.dec_degrees)
                    if await session.send(command) != Acknowledge():
                        acknowledge(f"error at {number}")
                        return
                    acknowledge(str(number))
                    if time.monotonic() > stop:
                        return

    asyncio.run(store())


WRITERS: dict[str, Callable[..., None]] = {
    "config": config_writer,
    "unique_id": unique_id_server,
    "commander": commander_writer,
}


# --- the zygote -----------------------------------------------------------------------------------


def _run_child(request: dict[str, Any]) -> None:
    descriptor = os.open(request["acks"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_APPEND)
    pid = os.fork()
    if pid == 0:  # the writer
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)  # stdout is the zygote's answer channel

        def acknowledge(text: str) -> None:
            os.write(descriptor, f"{text}\n".encode())  # one small write: whole or absent

        status = 0
        try:
            WRITERS[request["writer"]](*request["arguments"], acknowledge)
        except BaseException:
            traceback.print_exc()
            status = 1
        os._exit(status)
    os.close(descriptor)
    time.sleep(request["delay"])
    os.kill(pid, signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    killed = os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL
    _say({"pid": pid, "killed": killed})


def _say(answer: dict[str, Any]) -> None:
    sys.stdout.write(json.dumps(answer) + "\n")
    sys.stdout.flush()


def serve_forks() -> None:
    """The zygote: import what the writers need once, then fork one writer per request line."""
    import scopelink.cli.main
    import scopelink.servers.alpaca
    import scopelink.sim  # noqa: F401
    import tests.support.skytracker_emulator  # noqa: F401

    _say({"ready": True})
    for line in sys.stdin:
        _run_child(json.loads(line))


if __name__ == "__main__":
    serve_forks()
