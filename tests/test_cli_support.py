"""Helpers for the CLI tests: run ``scopelink`` as a user does, in a subprocess."""

from __future__ import annotations

import asyncio
import io
import json
import os
import re
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager, redirect_stdout
from pathlib import Path
from typing import Any

from scopelink.cli.main import main

RUN_TIMEOUT_S = 60
START_TIMEOUT_S = 20


def environment(config: Path) -> dict[str, str]:
    """The user's environment with the settings file at ``config`` (which need not exist)."""
    return {**os.environ, "SCOPELINK_CONFIG": str(config), "PYTHONUNBUFFERED": "1"}


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


def state_of(config: Path, device: str | None = None) -> dict[str, Any]:
    """The mount's state as ``scopelink status --json`` prints it (run in this process: a
    subprocess per reading would make the tests slow; the commands under test run apart)."""
    output = io.StringIO()
    saved = os.environ.get("SCOPELINK_CONFIG")
    os.environ["SCOPELINK_CONFIG"] = str(config)
    try:
        with redirect_stdout(output):
            status = main(["status", "--json", *(["--device", device] if device else [])])
    finally:
        if saved is None:
            del os.environ["SCOPELINK_CONFIG"]
        else:
            os.environ["SCOPELINK_CONFIG"] = saved
    assert status == 0, output.getvalue()
    state: dict[str, Any] = json.loads(output.getvalue())
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


async def read_line_matching(stream: asyncio.StreamReader | None, pattern: str) -> str:
    """The first line of ``stream`` that matches ``pattern`` (fails at end of stream)."""
    assert stream is not None
    seen: list[str] = []
    async with asyncio.timeout(START_TIMEOUT_S):
        while True:
            line = (await stream.readline()).decode()
            assert line, f"the stream ended before a line matching {pattern!r}: {seen}"
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
