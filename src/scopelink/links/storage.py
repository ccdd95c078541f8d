"""Files that survive a restart and a ``kill -9``: the emulated devices' memory, Alpaca's UniqueID,
the settings file.

Every write goes to a temporary file in the same directory, is flushed and fsynced, then
atomically renamed over the old file (and the directory is fsynced), so a reader always finds
either the old contents or the new ones, never a torn file.

A process killed between creating its temporary file and the rename leaves that file behind.
Temporary names carry the writer's process id (``.config.toml.<pid>.<random>.tmp``) so the next
write can tell a dead writer's leftover from a live concurrent writer's file and remove only
the former: leftovers never pile up beyond one per crash since the last write.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import time
from pathlib import Path
from typing import Final

__all__ = ["create_atomically", "remove_stale_temporaries", "temporaries_of", "write_atomically"]

_STALE_AFTER_S: Final = 3600.0
"""Where a writer's liveness cannot be asked (Windows), a leftover this old is stale."""


def write_atomically(path: Path, data: bytes) -> None:
    """Replace ``path`` with ``data`` so that a crash leaves the old file or the new, never half.

    An existing file keeps its permission bits (a temporary file is created 0600).
    """
    temporary = _write_temporary(path, data)
    try:
        with contextlib.suppress(FileNotFoundError):
            os.chmod(temporary, os.stat(path).st_mode & 0o7777)
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise
    _sync_directory(path.parent)


def create_atomically(path: Path, data: bytes) -> None:
    """Write ``path`` whole, or raise :class:`FileExistsError` and leave an existing file alone.

    The complete file is hard-linked into place, which fails if the name exists: no window in
    which another writer's file could be overwritten, and never a half-written file.
    """
    temporary = _write_temporary(path, data)
    try:
        try:
            os.link(temporary, path)
        except FileExistsError:
            raise
        except OSError:
            # A filesystem without hard links (FAT, some network shares): check, then rename.
            if path.exists():
                raise FileExistsError(f"{path} exists") from None
            os.replace(temporary, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
    _sync_directory(path.parent)


def temporaries_of(path: Path) -> list[Path]:
    """The temporary files (ours or a dead writer's) next to ``path``."""
    prefix, suffix = f".{path.name}.", ".tmp"
    try:
        names = os.listdir(path.parent)
    except FileNotFoundError:
        return []
    return sorted(
        path.parent / name for name in names if name.startswith(prefix) and name.endswith(suffix)
    )


def remove_stale_temporaries(path: Path) -> list[Path]:
    """Remove what writers killed mid-write left next to ``path``; returns what was removed."""
    removed: list[Path] = []
    for temporary in temporaries_of(path):
        if _is_stale(temporary, path):
            with contextlib.suppress(FileNotFoundError):
                temporary.unlink()
                removed.append(temporary)
    return removed


def _is_stale(temporary: Path, path: Path) -> bool:
    middle = temporary.name[len(path.name) + 2 : -len(".tmp")]
    pid_text = middle.split(".", 1)[0]
    if os.name == "posix" and pid_text.isdigit():
        pid = int(pid_text)
        if pid == os.getpid():
            return False  # a write of this process in another thread
        try:
            os.kill(pid, 0)  # signal 0: only asks whether the process exists
        except ProcessLookupError:
            return True
        except PermissionError:
            return False  # alive, another user's
        return False
    try:
        return time.time() - temporary.stat().st_mtime > _STALE_AFTER_S
    except FileNotFoundError:
        return False


def _write_temporary(path: Path, data: bytes) -> str:
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(path)
    descriptor, temporary = tempfile.mkstemp(
        prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent
    )
    try:
        with os.fdopen(descriptor, "wb") as file:
            file.write(data)
            file.flush()
            os.fsync(file.fileno())
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise
    return temporary


def _sync_directory(directory: Path) -> None:
    if os.name != "posix":
        return  # directories cannot be opened (nor need fsync) on Windows
    descriptor = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(descriptor)
    finally:
        os.close(descriptor)
