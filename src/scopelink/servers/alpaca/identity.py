"""The device's Alpaca UniqueID: a UUID4 made once and kept forever in a state directory.

Clients (NINA, ConformU's discovery map) recognise a device by its UniqueID across restarts and
address changes, so it must never change. It is written atomically (temporary file, fsync,
``os.replace``, fsync of the directory) so a crash never leaves a half-written file; a file that
exists but cannot be read is reported, never silently replaced.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
import uuid
from pathlib import Path

__all__ = ["UNIQUE_ID_FILE", "default_state_dir", "load_or_create_unique_id"]

UNIQUE_ID_FILE = "alpaca-telescope-0.json"


def default_state_dir() -> Path:
    """``$XDG_STATE_HOME/scopelink``, or ``~/.local/state/scopelink``."""
    base = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
    return Path(base) / "scopelink"


def load_or_create_unique_id(state_dir: Path) -> str:
    """The UniqueID stored in ``state_dir``; made and stored on first use."""
    path = state_dir / UNIQUE_ID_FILE
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        unique_id = str(uuid.uuid4())
        _write_atomically(path, json.dumps({"UniqueID": unique_id}) + "\n")
        return unique_id
    try:
        unique_id = str(json.loads(text)["UniqueID"])
        uuid.UUID(unique_id)
    except (ValueError, KeyError, TypeError) as error:
        raise ValueError(
            f"{path} does not hold an Alpaca UniqueID ({error}); fix or delete it (deleting it "
            "gives the telescope a new identity that clients will see as a new device)"
        ) from None
    return unique_id


def _write_atomically(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor, temporary = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(descriptor, "w", encoding="utf-8") as file:
            file.write(text)
            file.flush()
            os.fsync(file.fileno())
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise
    directory = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(directory)
    finally:
        os.close(directory)
