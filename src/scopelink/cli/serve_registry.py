"""Where a running ``scopelink serve`` says it is, so that the CLI drives the same mount.

Each serve writes ``serve-PID.json`` (mode 0600) into this user's runtime directory
(``$XDG_RUNTIME_DIR/scopelink``, else ``scopelink-UID`` under the temporary directory, mode
0700) once its servers listen, and removes it when it stops. A file is believed only when it is
this user's, in a directory only this user can write, and its process is alive, this user's and
the one that wrote it (the process start time in ``/proc`` matches); anything else is ignored,
so a serve another user started is never found, and a stale file (``kill -9``) is harmless.
Light: the CLI reads this before it knows whether a device is needed.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import stat
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

__all__ = ["ServeEntry", "register_serve", "running_serves", "runtime_dir", "unregister_serve"]

_PREFIX: Final = "serve-"
_log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class ServeEntry:
    """A running serve of this user: its PID and what it wrote about itself."""

    pid: int
    dashboard: str | None
    """The dashboard's URL as this machine reaches it (None: the dashboard is off)."""
    about: dict[str, Any]


def runtime_dir() -> Path:
    """This user's directory for the registration files (not created here)."""
    base = os.environ.get("XDG_RUNTIME_DIR")
    if base and Path(base).is_dir():
        return Path(base) / "scopelink"
    uid = os.getuid() if hasattr(os, "getuid") else 0
    return Path(tempfile.gettempdir()) / f"scopelink-{uid}"


def _private_dir(create: bool) -> Path | None:
    """The runtime directory if it is ours and nobody else may write in it."""
    directory = runtime_dir()
    if create:
        with contextlib.suppress(FileExistsError):
            directory.mkdir(mode=0o700, parents=True)
    try:
        info = directory.lstat()
    except OSError:
        return None
    if not stat.S_ISDIR(info.st_mode) or not _ours(info) or info.st_mode & 0o022:
        return None
    return directory


def _ours(info: os.stat_result) -> bool:
    return not hasattr(os, "getuid") or info.st_uid == os.getuid()


def register_serve(about: dict[str, Any]) -> Path | None:
    """Write this process's registration; its path (None, logged, when it cannot be written:
    the serve runs on, the command line just does not find it)."""
    try:
        return _write(about)
    except OSError as error:
        _log.warning("the command line will not find this serve: %s", error)
        return None


def _write(about: dict[str, Any]) -> Path | None:
    directory = _private_dir(create=True)
    if directory is None:
        _log.warning("the command line will not find this serve: %s is not private", runtime_dir())
        return None
    pid = os.getpid()
    entry = {**about, "pid": pid, "start_ticks": _start_ticks(pid)}
    path = directory / f"{_PREFIX}{pid}.json"
    scratch = directory / f".{_PREFIX}{pid}.tmp"
    descriptor = os.open(scratch, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(descriptor, "w", encoding="utf-8") as file:
        json.dump(entry, file)
    os.replace(scratch, path)
    return path


def unregister_serve(path: Path | None) -> None:
    if path is not None:
        with contextlib.suppress(OSError):
            path.unlink()


def running_serves() -> list[ServeEntry]:
    """This user's running serves, oldest PID first; stale or foreign files are ignored."""
    directory = _private_dir(create=False)
    if directory is None:
        return []
    found: list[ServeEntry] = []
    for path in sorted(directory.glob(f"{_PREFIX}*.json")):
        entry = _read(path)
        if entry is not None:
            found.append(entry)
    return sorted(found, key=lambda entry: entry.pid)


def _read(path: Path) -> ServeEntry | None:
    try:
        if not _ours(path.lstat()) or path.is_symlink():
            return None
        about = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(about, dict):
        return None
    pid = about.get("pid")
    if not isinstance(pid, int) or isinstance(pid, bool) or not _alive_and_ours(pid):
        return None
    ticks = _start_ticks(pid)
    if ticks is not None and about.get("start_ticks") != ticks:
        return None  # the PID was reused by another process
    dashboard = about.get("dashboard")
    return ServeEntry(pid, dashboard if isinstance(dashboard, str) else None, about)


def _alive_and_ours(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except PermissionError:
        return False  # alive, but another user's
    except OSError:
        return False
    if not Path("/proc/self").exists():
        return True  # no /proc (macOS): kill(pid, 0) is all there is
    try:
        return _ours(os.stat(f"/proc/{pid}"))
    except OSError:
        return False


def _start_ticks(pid: int) -> int | None:
    """The process's start time in clock ticks since boot (Linux), to tell a reused PID."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text.rpartition(")")[2].split()
    try:
        return int(fields[19])  # field 22 of stat(5); fields[0] is field 3
    except (IndexError, ValueError):
        return None
