"""What scopelink remembers about one device between runs: small JSON records (where it was
parked, its pointing corrections...) in the per-user state directory, one directory per device.

A device is known by a key its driver gives (e.g. ``synscan-<model>-<port>``): the same mount on the
same port finds its records again after a restart or a power cycle. Records are written atomically
(:mod:`scopelink.links.storage`), so a crash or ``kill -9`` leaves the old record or the new one,
never a torn file. A record that cannot be read back (edited by hand, from a newer version) is
reported as one clear error naming the file, and is never silently replaced.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import Any

from scopelink.links.storage import remove_stale_temporaries, write_atomically

__all__ = ["DeviceMemory", "RecordError", "default_state_dir"]


def default_state_dir() -> Path:
    """``$XDG_STATE_HOME/scopelink``, or ``~/.local/state/scopelink``."""
    base = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
    return Path(base) / "scopelink"


class RecordError(ValueError):
    """A stored record cannot be read: the message names the file and what to do."""


_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


class DeviceMemory:
    """The records of one device: ``load``/``save``/``forget`` by record name."""

    def __init__(self, device_key: str, state_dir: Path | None = None) -> None:
        key = _UNSAFE.sub("_", device_key).strip("._") or "device"
        self.directory = (state_dir or default_state_dir()) / "devices" / key

    def path(self, name: str) -> Path:
        return self.directory / f"{name}.json"

    def load(self, name: str) -> dict[str, Any] | None:
        """The record ``name``, or None when there is none."""
        path = self.path(name)
        remove_stale_temporaries(path)
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return None
        try:
            record = json.loads(text)
        except ValueError as error:
            raise RecordError(f"{path} is not readable JSON ({error}); fix or delete it") from None
        if not isinstance(record, dict):
            raise RecordError(f"{path} does not hold a record; fix or delete it")
        return record

    def save(self, name: str, record: dict[str, Any]) -> None:
        self.directory.mkdir(parents=True, exist_ok=True)
        text = json.dumps(record, indent=1, sort_keys=True) + "\n"
        write_atomically(self.path(name), text.encode("utf-8"))

    def forget(self, name: str) -> None:
        self.path(name).unlink(missing_ok=True)
