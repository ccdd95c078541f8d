"""Helpers for the CLI tests: run ``scopelink`` as a user does, in a subprocess."""

from __future__ import annotations

import asyncio
import io
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from pathlib import Path
from typing import Any

from scopelink.cli.main import main

RUN_TIMEOUT_S = 60
START_TIMEOUT_S = 20


def environment(config: Path) -> dict[str, str]:
    """The user's environment with the settings file at ``config`` (which need not exist)."""
    state = str(config.parent / "state")  # park records stay out of the user's own directory
    return {
        **os.environ,
        "SCOPELINK_CONFIG": str(config),
        "PYTHONUNBUFFERED": "1",
        "XDG_STATE_HOME": state,
    }


def scopelink(config: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """Run ``scopelink ARGS`` to the end (stdin closed), capturing its output as text."""
    return subprocess.run(
        [sys.executable, "-m", "scopelink", *args],
        env=environment(config),
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )


def scopelink_here(config: Path, *args: str) -> tuple[int, str, str]:
    """``scopelink ARGS`` through :func:`main` in this process (status, stdout, stderr): cheaper
    than a subprocess where the process boundary is not what a test is about."""
    out, err = io.StringIO(), io.StringIO()
    saved = os.environ.get("SCOPELINK_CONFIG")
    os.environ["SCOPELINK_CONFIG"] = str(config)
    try:
        with redirect_stdout(out), redirect_stderr(err):
            status = main(list(args))
    finally:
        if saved is None:
            del os.environ["SCOPELINK_CONFIG"]
        else:
            os.environ["SCOPELINK_CONFIG"] = saved
    return status, out.getvalue(), err.getvalue()


def state_of(config: Path, device: str | None = None) -> dict[str, Any]:
    """The mount's state as ``scopelink status --json`` prints it (in this process)."""
    status, out, err = scopelink_here(
        config, "status", "--json", *(["--device", device] if device else [])
    )
    assert status == 0, err
    state: dict[str, Any] = json.loads(out)
    return state


async def start_scopelink(config: Path, *args: str) -> asyncio.subprocess.Process:
    """Start ``scopelink ARGS`` with its stdout and stderr piped, for tests that signal it."""
    return await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "scopelink",
        *args,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
        env=environment(config),
    )


async def read_line_matching(
    stream: asyncio.StreamReader | None,
    pattern: str,
    errors: asyncio.StreamReader | None = None,
) -> str:
    """The first line of ``stream`` that matches ``pattern`` (fails at end of stream, quoting
    ``errors``, the process's stderr, when given)."""
    assert stream is not None
    seen: list[str] = []
    async with asyncio.timeout(START_TIMEOUT_S):
        while True:
            line = (await stream.readline()).decode()
            if not line:
                stderr = (await errors.read()).decode() if errors is not None else ""
                raise AssertionError(
                    f"the stream ended before a line matching {pattern!r}: {seen} {stderr}"
                )
            if re.search(pattern, line):
                return line
            seen.append(line)


@contextmanager
def synscan_emulator(*options: str) -> Iterator[str]:
    """A ``scopelink emulate synscan`` subprocess on a free TCP port; yields its device string."""
    with emulator("synscan", *options) as device:
        yield device


@contextmanager
def emulator(kind: str, *options: str) -> Iterator[str]:
    """A ``scopelink emulate KIND`` subprocess on a free TCP port; yields its device string."""
    process = subprocess.Popen(
        [sys.executable, "-m", "scopelink", "emulate", kind, "--tcp", "127.0.0.1:0", *options],
        stdout=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        match = re.search(r"listening on (127\.0\.0\.1:\d+)", line)
        assert match, f"the emulator printed {line!r}"
        yield f"{kind}:tcp://{match.group(1)}"
    finally:
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


_ANGLE = re.compile(r"([+-])(\d+)°(\d+)'(\d+)\"")


def degrees_in(text: str, label: str) -> float:
    """The angle printed after ``label`` (e.g. ``Alt +45°00'00"``), in degrees."""
    match = re.search(re.escape(label) + r" " + _ANGLE.pattern, text)
    assert match, f"no {label} angle in {text!r}"
    sign, whole, minutes, seconds = match.groups()
    value = int(whole) + int(minutes) / 60 + int(seconds) / 3600
    return -value if sign == "-" else value


def separation_deg(alt1: float, az1: float, alt2: float, az2: float) -> float:
    a1, z1, a2, z2 = (math.radians(value) for value in (alt1, az1, alt2, az2))
    cosine = math.sin(a1) * math.sin(a2) + math.cos(a1) * math.cos(a2) * math.cos(z1 - z2)
    return math.degrees(math.acos(max(-1.0, min(1.0, cosine))))


def settled_state(config: Path, device: str | None = None) -> dict[str, Any]:
    """A state once the axes have stopped: ``L`` says a cancelled goto is over while the motors
    still ramp down, so the position is read until two readings 0.2 s apart agree."""
    previous = state_of(config, device)
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        time.sleep(0.2)
        current = state_of(config, device)
        alt1, az1, alt2, az2 = (
            previous["alt_deg"],
            previous["az_deg"],
            current["alt_deg"],
            current["az_deg"],
        )
        if separation_deg(alt1, az1, alt2, az2) < 0.01:
            return current
        previous = current
    raise AssertionError("the mount never came to rest")
