"""`scopelink doctor`: each kind of thing on a port, told apart by read-only questions, against
the real emulators over ptys and small peers written here; a port without permission, one
locked by another process, ModemManager (a stub `systemctl`)."""

from __future__ import annotations

import asyncio
import json
import os
import pwd
import sys
import textwrap
import tty
from collections.abc import AsyncIterator, Callable
from contextlib import AsyncExitStack, asynccontextmanager
from pathlib import Path

import pytest

from scopelink.astro import Site
from scopelink.cli.doctor_command import examine
from scopelink.cli.doctor_port import modem_manager_note
from scopelink.links import open_pty
from scopelink.servers.faults import Fault, FaultInjector
from scopelink.servers.skytracker import SkyCommanderEmulator, SkyTrackerEmulator
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import PRESETS, SKY_TRACKER, SimClock, SimulatedMount
from tests.support.cli import scopelink_here

SITE = Site(40.4, -3.7)
WAIT_S = 1.0  # the default: what a user waits, robust on a loaded machine
# What a device would send: every byte it is sent, the reply (None: keeps quiet).
Peer = Callable[[bytes], bytes | None]
FORBIDDEN = frozenset(b"KGUTDBudlrbSsPrRHhWwMOL")  # motion or settings, SynScan or Sky Tracker


def motor_controller() -> Peer:
    """A SynScan motor controller: ':' commands ending in CR, everything else ignored."""
    buffer = bytearray()

    def answer(data: bytes) -> bytes | None:
        for byte in data:
            if byte == ord(":"):
                buffer.clear()
            buffer.append(byte)
        if buffer.startswith(b":e1\r"):
            buffer.clear()
            return b"=020B03\r"
        return None

    return answer


def nexstar(data: bytes) -> bytes | None:
    return {b"V": b"\x04\x15#", b"m": b"\x0b#"}.get(data)


def wrong_baud(data: bytes) -> bytes | None:
    return b"\xf0\x80\xfe\x9c"  # what 9600 baud reads of a device at another speed


@asynccontextmanager
async def peer(answer: Peer, received: list[bytes]) -> AsyncIterator[str]:
    pty = await open_pty()

    async def serve() -> None:
        while True:
            data = await pty.read()
            received.append(data)
            reply = answer(data)
            if reply:
                await pty.write(reply)

    task = asyncio.create_task(serve())
    try:
        yield pty.path
    finally:
        task.cancel()
        await pty.close()


async def test_each_device_is_told_apart_with_read_only_questions(tmp_path: Path) -> None:
    clock = SimClock(rate=1.0)
    received: dict[str, list[bytes]] = {}
    async with AsyncExitStack() as stack:
        synscan = await stack.enter_async_context(
            SynScanEmulator(
                SimulatedMount(PRESETS["eq6"], site=SITE, clock=clock),
                SynScanConfig(model=0, aligned=False),
                wire=None,
            )
        )
        mute_commander = FaultInjector([Fault.parse("any:drop:always")])
        trackers = [
            await stack.enter_async_context(
                SkyTrackerEmulator(
                    SimulatedMount(SKY_TRACKER, site=SITE, clock=clock),
                    tmp_path / name,
                    pace=False,
                    commander_faults=faults,
                )
            )
            for name, faults in (("with", None), ("without", mute_commander))
        ]
        commander = await stack.enter_async_context(
            SkyCommanderEmulator(
                SimulatedMount(SKY_TRACKER, site=SITE, clock=clock), tmp_path / "sc", pace=False
            )
        )
        ports = {
            "synscan": await synscan.on_pty(),
            "skytracker": await trackers[0].on_pty(),
            "skytracker alone": await trackers[1].on_pty(),
            "skycommander": await commander.on_pty(),
        }
        peers: dict[str, Peer] = {
            "motor controller": motor_controller(),
            "nexstar": nexstar,
            "wrong baud": wrong_baud,
            "silence": lambda data: None,
        }
        for name, answer in peers.items():
            received[name] = []
            ports[name] = await stack.enter_async_context(peer(answer, received[name]))
        names = list(ports)
        results = await asyncio.gather(*(examine(ports[name], WAIT_S) for name in names))
        found = dict(zip(names, results, strict=True))

    assert {name: finding.kind for name, finding in found.items()} == {
        "synscan": "synscan",
        "skytracker": "skytracker",
        "skytracker alone": "skytracker",
        "skycommander": "skycommander",
        "motor controller": "synscan-motor-controller",
        "nexstar": "nexstar",
        "wrong baud": "garbage",
        "silence": "nothing",
    }
    hand = found["synscan"]
    assert "firmware 04.39.05, model EQ6 GOTO (code 0), NOT aligned, not in PC-Direct" in hand.what
    assert hand.device == f"synscan:{ports['synscan']}"
    assert hand.usable
    assert "finish the star alignment" in hand.advice
    assert "with its Sky Commander answering" in found["skytracker"].what
    assert "with NO Sky Commander answering" in found["skytracker alone"].what
    assert found["skycommander"].device == f"skycommander:{ports['skycommander']}"
    assert "the hand control is not in between" in found["motor controller"].what
    assert "Celestron NexStar hand control, firmware 4.21" in found["nexstar"].what
    assert not found["nexstar"].usable
    assert "line speed is probably wrong" in found["wrong baud"].what
    assert "f0 80 fe 9c" in found["wrong baud"].what
    # Read-only: what the peers received holds no motion or setting command.
    assert b"".join(received["silence"]) == b"V\r:e1\r"
    sent = b"".join(b"".join(chunks) for chunks in received.values())
    assert not set(sent.replace(b":e1\r", b"")) & FORBIDDEN
    # The emulated mounts did not move.
    assert synscan.mount.state.slewing is False


def test_a_port_without_permission_names_the_group_and_the_command(tmp_path: Path) -> None:
    """A real open refused by the kernel: as `nobody` (root would bypass the mode)."""
    master, slave = os.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)
    os.chmod(path, 0o000)
    nobody = pwd.getpwnam("nobody")
    read_end, write_end = os.pipe()
    child = os.fork()
    if child == 0:  # pragma: no cover - the child reports through the pipe
        try:
            if os.geteuid() == 0:  # root opens anything: be nobody (others are refused as is)
                os.setgroups([])
                os.setgid(nobody.pw_gid)
                os.setuid(nobody.pw_uid)
            finding = asyncio.run(examine(path, WAIT_S))
            os.write(write_end, json.dumps([finding.kind, finding.what, finding.advice]).encode())
        finally:
            os._exit(0)
    os.close(write_end)
    with os.fdopen(read_end) as pipe:
        kind, what, advice = json.loads(pipe.read())
    os.waitpid(child, 0)
    os.close(master)
    os.close(slave)
    assert kind == "permission"
    assert what == f"you may not open {path} (permission denied; the port belongs to group dialout)"
    assert advice.startswith("run: sudo usermod -aG dialout $USER   then log out and in again")


async def test_a_locked_port_names_the_process_holding_it() -> None:
    pty = await open_pty()
    holder = await asyncio.create_subprocess_exec(
        sys.executable,
        "-c",
        textwrap.dedent(
            f"""
            import fcntl, os, sys, time
            fd = os.open({pty.path!r}, os.O_RDWR | os.O_NOCTTY)
            fcntl.flock(fd, fcntl.LOCK_EX)
            print("held", flush=True)
            time.sleep(30)
            """
        ),
        stdout=asyncio.subprocess.PIPE,
    )
    try:
        assert holder.stdout is not None
        async with asyncio.timeout(20):
            assert await holder.stdout.readline() == b"held\n"
        name = Path(f"/proc/{holder.pid}/comm").read_text().strip()  # noqa: ASYNC240
        finding = await examine(pty.path, WAIT_S)
    finally:
        holder.kill()
        await holder.wait()
        await pty.close()
    assert finding.kind == "busy"
    assert finding.what == f"{pty.path} is in use by {name} (PID {holder.pid})"


def test_modem_manager_running_is_reported_with_the_udev_hint(
    tmp_path: Path, config: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    systemctl = bin_dir / "systemctl"
    systemctl.write_text('#!/bin/sh\n[ "$1 $2" = "is-active ModemManager" ] && echo active\n')
    systemctl.chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}:{os.environ['PATH']}")
    master, slave = os.openpty()
    try:
        tty.setraw(slave)
        status, out, _ = scopelink_here(config, "doctor", os.ttyname(slave), "--wait", "0.1")
        status_json, out_json, _ = scopelink_here(
            config, "doctor", os.ttyname(slave), "--wait", "0.1", "--json"
        )
    finally:
        os.close(master)
        os.close(slave)
    assert status == status_json == 1  # nothing scopelink drives answered
    assert "found: nothing answered" in out
    assert "note: ModemManager is running" in out
    assert 'ENV{ID_MM_DEVICE_IGNORE}="1"' in out
    report = json.loads(out_json)
    assert report["kind"] == "nothing"
    assert report["usable"] is False
    assert report["modem_manager"] == modem_manager_note()
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    assert modem_manager_note() is None


def test_documented_defaults_are_the_code_s() -> None:
    from scopelink.cli.doctor_probe import FIRST_BYTE_WAIT_S, QUIET_S

    docs = (Path(__file__).parents[2] / "docs" / "cli.md").read_text()
    assert f"`--wait` seconds (default **{FIRST_BYTE_WAIT_S:g} s**, 0.05-10)" in docs
    assert f"after **{QUIET_S:g} s** of quiet" in docs
