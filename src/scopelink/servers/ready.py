"""What an emulated device says about itself once it serves: where, what, which firmware.

``scopelink emulate ... --ready-json`` prints :func:`ready_json` as its one line on stdout, and the
handles of :mod:`scopelink.testing` carry :func:`announcement` (docs/testing-with-scopelink.md).
"""

from __future__ import annotations

import json
import os

from scopelink.servers.hosting import HostedDevice
from scopelink.servers.skytracker import SkyCommanderEmulator, SkyTrackerEmulator
from scopelink.servers.skytracker.tracker import VERSION as SKY_TRACKER_VERSION
from scopelink.servers.synscan import SynScanEmulator

__all__ = ["announcement", "ready_json"]


def announcement(
    protocol: str, device: HostedDevice, address: str | None = None
) -> dict[str, object]:
    """Where and what ``device`` (a started emulator of ``protocol``) is; ``address`` when
    another host serves it (default: its own).

    Keys: ``protocol``; ``tcp`` (``HOST:PORT``) or ``pty`` (the path); ``device``, the scopelink
    device string (``synscan:tcp://127.0.0.1:PORT``); ``model`` and ``firmware`` as the device
    reports them; ``pid``, this process.
    """
    address = address if address is not None else device.address
    where = "pty" if address.startswith("/") else "tcp"
    link = address if where == "pty" else f"tcp://{address}"
    found: dict[str, object] = {
        "protocol": protocol,
        where: address,
        "device": f"{protocol}:{link}",
    }
    if isinstance(device, SynScanEmulator):
        config = device.hand_control.config
        found["model"] = device.mount.identity.model
        found["model_code"] = config.model
        firmware = config.firmware
        found["firmware"] = f"{firmware.major}.{firmware.minor:02}.{firmware.patch:02}"
    elif isinstance(device, SkyTrackerEmulator):
        found["model"] = "Sky Tracker"
        found["firmware"] = SKY_TRACKER_VERSION.text.strip()
    elif isinstance(device, SkyCommanderEmulator):
        found["model"] = "Sky Commander"
    found["pid"] = os.getpid()
    return found


def ready_json(protocol: str, device: HostedDevice) -> str:
    """:func:`announcement` as one line of JSON."""
    return json.dumps(announcement(protocol, device), separators=(", ", ": "))
