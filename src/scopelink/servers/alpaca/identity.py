"""The device's Alpaca UniqueID: a UUID4 made once and kept forever in a state directory.

Clients (NINA, ConformU's discovery map) recognise a device by its UniqueID across restarts and
address changes, so it must never change. It is written atomically
(:func:`scopelink.links.storage.write_atomically`), so a crash never leaves a half-written
file; a file that exists but cannot be read is reported, never silently replaced.
"""

from __future__ import annotations

import json
import uuid
from pathlib import Path

from scopelink.links.storage import remove_stale_temporaries, write_atomically
from scopelink.mount.memory import default_state_dir

__all__ = ["UNIQUE_ID_FILE", "default_state_dir", "load_or_create_unique_id"]

UNIQUE_ID_FILE = "alpaca-telescope-0.json"


def load_or_create_unique_id(state_dir: Path) -> str:
    """The UniqueID stored in ``state_dir``; made and stored on first use."""
    path = state_dir / UNIQUE_ID_FILE
    remove_stale_temporaries(path)  # what a kill -9 during the first start left
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        unique_id = str(uuid.uuid4())
        write_atomically(path, (json.dumps({"UniqueID": unique_id}) + "\n").encode())
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
