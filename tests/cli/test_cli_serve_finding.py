"""One mount for every front end: the command line finds the running `scopelink serve` of this
user (its runtime file) and drives that serve's mount, through the serve's own guard."""

from __future__ import annotations

import asyncio
import fcntl
import json
import os
import re
import signal
import subprocess
import sys
import time
from argparse import Namespace
from collections.abc import Callable
from pathlib import Path

import pytest

from scopelink.cli.errors import CommandError
from scopelink.cli.mount_session import DeviceCommand
from scopelink.cli.serve_registry import register_serve, running_serves, unregister_serve
from scopelink.cli.stopping import until_stopped
from scopelink.drivers.open import DeviceSpec
from tests.support.cli import environment, scopelink_here

SERVERS_OFF = (
    "--discovery-port=-1",
    "--lx200-port=-1",
    "--skyfi-port=-1",
    "--stellarium-port=-1",
    "--synscan-port=-1",
    "--alpaca-port=-1",
)


def test_park_then_status_agree_through_the_running_serve(config: Path, runtime_dir: Path) -> None:
    serve = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "scopelink",
            "serve",
            "--clock-rate",
            "100",
            *SERVERS_OFF,
            "--dashboard-port=0",
        ],
        env=environment(config),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
    )
    try:
        assert serve.stdout is not None
        printed: list[str] = []
        while (line := serve.stdout.readline()) and line != "Ctrl-C stops.\n":
            printed.append(line)  # ends at EOF if the serve failed to start
        assert line == "Ctrl-C stops.\n", printed
        (registration,) = (runtime_dir / "scopelink").glob("serve-*.json")
        assert registration.stat().st_mode & 0o777 == 0o600
        about = json.loads(registration.read_text())
        assert about["pid"] == serve.pid
        assert about["device"] == "sim:eq6"
        assert re.fullmatch(r"http://127\.0\.0\.1:\d+", about["dashboard"])

        assert scopelink_here(config, "park")[0] == 0  # no --device: the serve's mount
        status, out, err = scopelink_here(config, "status", "--json")
        assert status == 0, err
        assert json.loads(out)["parked"] is True
        # The serve's guard holds for commands that come this way.
        status, _, err = scopelink_here(config, "goto", "--altaz", "30", "180", "--device", "serve")
        assert status == 1
        assert "parked" in err
        assert scopelink_here(config, "unpark")[0] == 0
        status, _, err = scopelink_here(config, "goto", "--altaz", "-5", "180")
        assert status == 1
        assert "hint: the horizon and limits are set in the config file" in err
        # A `move` whose terminal goes (an SSH session dropped: SIGHUP) stops the axis it moved;
        # so does one killed outright (its live connection to the serve is the dead-man's).
        for kill in (signal.SIGHUP, signal.SIGKILL):
            mover = subprocess.Popen(
                [sys.executable, "-m", "scopelink", "move", "ra", "8x"],
                env=environment(config),
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                stdin=subprocess.DEVNULL,
                text=True,
            )
            assert mover.stdout is not None
            assert "moving the primary axis" in mover.stdout.readline()
            assert _state(config)["slewing"] is True
            mover.send_signal(kill)
            assert mover.wait(timeout=20) == (0 if kill == signal.SIGHUP else -kill)
            _wait_until(lambda: _state(config)["slewing"] is False, "the axis stops")
        # What the serve's API does not offer is refused in one line, never attempted.
        status, _, err = scopelink_here(config, "guide", "north", "100")
        assert status == 1
        assert f"cannot be done through a running scopelink serve (PID {serve.pid})" in err
        # Following runs where the mount is driven: said so, not "cannot track at custom rates".
        status, _, err = scopelink_here(config, "track", "moon")
        assert status == 1
        assert (
            f"following: cannot be done through a running scopelink serve (PID {serve.pid})" in err
        )
        assert "POST /api/track" in err
        assert "custom rates" not in err
        # `pointing` (which talks to the dashboard itself) finds the same serve without --url.
        status, out, err = scopelink_here(config, "pointing", "--json")
        assert status == 0, err
        assert "syncs" in json.loads(out)
        status, _, err = scopelink_here(config, "status", "--device", "serve:1")
        assert status == 1
        assert "no scopelink serve with PID 1 is running" in err
    finally:
        serve.send_signal(signal.SIGINT)
        assert serve.wait(timeout=20) == 0
    assert not list((runtime_dir / "scopelink").glob("serve-*.json"))  # removed at exit
    status, _, err = scopelink_here(config, "status")
    assert status == 1
    assert "no device given, and no scopelink serve is running" in err
    assert "hint: start 'scopelink serve' (the commands then drive its mount)" in err


def test_only_a_live_serve_of_this_user_is_found(
    config: Path, runtime_dir: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("SCOPELINK_CONFIG", str(config))
    path = register_serve({"device": "synscan:/dev/ttyFAKE", "dashboard": "http://127.0.0.1:9"})
    assert path is not None
    assert [entry.pid for entry in running_serves()] == [os.getpid()]
    args = Namespace(device=None, site=None, timeout=None, clock_rate=1.0, command="status")
    # The config names the device this serve holds: the serve's mount, not a busy port.
    config.write_text('device = "synscan:/dev/ttyFAKE"\n')
    assert DeviceCommand.from_args(args).device == DeviceSpec("serve", str(os.getpid()))
    # Naming that device while the serve holds it: a busy port, and the way to the serve.
    master, slave = os.openpty()
    fcntl.flock(slave, fcntl.LOCK_EX)
    held = os.ttyname(slave)
    unregister_serve(path)
    path = register_serve({"device": f"synscan:{held}", "dashboard": "http://127.0.0.1:9"})
    assert path is not None
    status, _, err = scopelink_here(config, "status", "--device", f"synscan:{held}")
    os.close(master)
    os.close(slave)
    assert status == 1
    assert "port busy" in err
    assert f"hint: scopelink serve (PID {os.getpid()}) holds it: give --device serve" in err
    config.write_text('device = "sim"\n')  # a simulator lives in the command's own process
    assert DeviceCommand.from_args(args).device == DeviceSpec("sim", "eq6")
    with pytest.raises(CommandError, match="cannot drive another serve's mount"):
        DeviceCommand.from_args(
            Namespace(**{**vars(args), "device": "serve"}), default_device="sim"
        )

    entry = json.loads(path.read_text())
    forged = path.with_name("serve-1.json")  # PID 1 is alive, but not this serve
    forged.write_text(json.dumps({**entry, "pid": 1}))
    stale = path.with_name("serve-999999999.json")  # long gone (kill -9 left it)
    stale.write_text(json.dumps({**entry, "pid": 999999999}))
    reused = path.with_name("serve-reused.json")  # the PID now names another process
    reused.write_text(json.dumps({**entry, "start_ticks": entry["start_ticks"] - 1}))
    assert [entry.pid for entry in running_serves()] == [os.getpid()]
    if os.geteuid() == 0:  # CI: root can make the file another user's
        os.chown(path, 65534, 65534)  # another user's file: never believed
        assert running_serves() == []
    unregister_serve(path)
    os.chmod(runtime_dir / "scopelink", 0o777)  # a directory others may write in: not trusted
    register_serve(entry)
    assert running_serves() == []


def test_documented_defaults_are_the_code_s() -> None:
    from scopelink.cli.serve_mount import POLL_S, REQUEST_TIMEOUT_S

    docs = (Path(__file__).parents[2] / "docs" / "cli.md").read_text()
    assert f"reads the serve every **{POLL_S:g} s**" in docs
    assert f"each request may take **{REQUEST_TIMEOUT_S:g} s**" in docs


def _state(config: Path) -> dict[str, object]:
    status, out, err = scopelink_here(config, "status", "--json")
    assert status == 0, err
    state: dict[str, object] = json.loads(out)
    return state


async def test_an_ignored_hangup_stays_ignored() -> None:
    """Under ``nohup`` a serve must not end when the terminal goes."""
    previous = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        async with until_stopped():
            assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
        signal.signal(signal.SIGHUP, signal.SIG_DFL)
        async with until_stopped() as stop:
            os.kill(os.getpid(), signal.SIGHUP)
            async with asyncio.timeout(5):
                await stop.wait()
    finally:
        signal.signal(signal.SIGHUP, previous)


def _wait_until(check: Callable[[], bool], what: str, timeout_s: float = 5.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not check():
        assert time.monotonic() < deadline, f"timed out waiting for: {what}"
        time.sleep(0.05)
