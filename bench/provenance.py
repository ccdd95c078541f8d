"""Where a benchmark's figures come from: date, load average, cores and commit, printed with every
report so that each figure in docs/benchmarks.md can be traced to the code that produced it."""

from __future__ import annotations

import importlib.metadata
import os
import platform
import subprocess
from datetime import UTC, datetime


def git(*args: str) -> str:
    """``git args...``'s output, or "unknown" outside a checkout."""
    try:
        done = subprocess.run(["git", *args], capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return done.stdout.strip()


def provenance() -> list[str]:
    """Two lines: when and under what load, and which commit (marked if src/ or bench/ have
    uncommitted changes) with which Python."""
    dirty = "+uncommitted changes" if git("status", "--porcelain", "--", "src", "bench") else ""
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    return [
        f"date {datetime.now(UTC):%Y-%m-%d %H:%M} UTC, "
        f"load average {load} on {os.cpu_count()} cores",
        f"commit {git('rev-parse', '--short', 'HEAD')}{dirty}, Python {platform.python_version()}",
    ]


def print_provenance(*more: str) -> None:
    """Print :func:`provenance` (and any ``more`` lines: the peers' versions): the first lines of
    every benchmark's report."""
    for line in (*provenance(), *more):
        print(line, flush=True)


def installed_version(distribution: str) -> str:
    """The installed version of ``distribution`` in this environment, or "not installed"."""
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def pin_problem(name: str, version: str, pin: str, any_version: bool) -> str | None:
    """Why a peer may not be measured: its version is not ``pin`` (unless ``any_version``, and
    then the report must say so: see :func:`peer_label`)."""
    if version == pin or any_version:
        return None
    return (
        f"the peer {name} is version {version}, not the pinned {pin}: install {name}=={pin}, "
        "or pass --any-peer-version"
    )


def peer_label(name: str, version: str, pin: str) -> str:
    """``name version (pin P)``, marked when it is not the pinned one."""
    return f"{name} {version} (pin {pin}" + (")" if version == pin else ": NOT the pinned version)")


UVLOOP_PIN = "0.23.0"
"""The uvloop release the driver benchmarks measure ``serve``'s loop on (the test extra pins the
same; the runtime dependency accepts any 0.x from 0.21)."""


def serve_loop(any_version: bool) -> tuple[str, str | None]:
    """The provenance line of the event loop ``scopelink serve`` runs on (``links.loops``), and
    why it may not be measured: uvloop not at :data:`UVLOOP_PIN` (unless ``any_version``) or
    absent. A loop chosen by ``SCOPELINK_EVENT_LOOP=asyncio`` is measured, and said."""
    from scopelink.links import EVENT_LOOP_ENV_VAR, choose_event_loop

    choice = choose_event_loop()
    if choice.name == "asyncio" and choice.reason.startswith(EVENT_LOOP_ENV_VAR):
        return f"serve's event loop: {choice.label}", None
    version = installed_version("uvloop")
    return (
        f"serve's event loop: {peer_label('uvloop', version, UVLOOP_PIN)}",
        pin_problem("uvloop", version, UVLOOP_PIN, any_version),
    )
