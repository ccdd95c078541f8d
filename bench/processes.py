"""``scopelink`` as a child process of a benchmark: the command line as users run it, with its own
settings (none) and state directory under ``home`` so that no user file is read or written."""

from __future__ import annotations

import asyncio
import os
import sys
from pathlib import Path


def environment(home: Path) -> dict[str, str]:
    """This process's environment with no settings file and a private state directory."""
    return {
        **os.environ,
        "PYTHONUNBUFFERED": "1",
        "SCOPELINK_CONFIG": str(home / "absent.toml"),
        "XDG_STATE_HOME": str(home / "state"),
    }


async def start_scopelink(
    home: Path, *args: str, stderr: int = asyncio.subprocess.PIPE
) -> asyncio.subprocess.Process:
    """``python -m scopelink args...``, its standard output piped (and its errors, unless
    ``stderr`` says otherwise: a long run that never reads them should pass DEVNULL)."""
    return await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "scopelink",
        *args,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=stderr,
        env=environment(home),
    )
