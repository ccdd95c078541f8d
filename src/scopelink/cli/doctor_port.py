"""Why a port will not open, said in words (``scopelink doctor``): missing, no permission (and
the exact command that grants it), in use (by which process, where ``/proc`` tells), and on
Linux whether ModemManager is running, which grabs new serial ports to look for modems."""

from __future__ import annotations

import grp
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from scopelink.cli.doctor_probe import Finding
from scopelink.links import LinkOpenError
from scopelink.links.serial import NO_SUCH_DEVICE, PERMISSION_DENIED, PORT_BUSY

__all__ = [
    "DEFAULT_GROUP",
    "Holder",
    "holders_of",
    "modem_manager_note",
    "open_failure",
]

DEFAULT_GROUP: Final = "dialout"
"""The group that may open serial ports on Debian, Ubuntu and Raspberry Pi OS."""
_SYSTEMCTL_TIMEOUT_S: Final = 3.0


@dataclass(frozen=True, slots=True)
class Holder:
    """A process that has the port open."""

    pid: int
    name: str

    def __str__(self) -> str:
        return f"{self.name} (PID {self.pid})"


def open_failure(port: str, error: BaseException) -> Finding:
    """What a failure to open ``port`` means and what to do, from the reason the link gave
    (``links.serial`` reads it from the errno of the real open, or the exclusive lock)."""
    reason = error.reason if isinstance(error, LinkOpenError) else None
    text = str(error)
    if reason == NO_SUCH_DEVICE:
        return Finding(
            "no-such-port",
            f"{port} does not exist",
            "plug the cable in; 'scopelink ports' lists the serial ports there are",
        )
    if reason == PERMISSION_DENIED:
        group = _group_of(port)
        return Finding(
            "permission",
            f"you may not open {port} (permission denied; the port belongs to group {group})",
            f"run: sudo usermod -aG {group} $USER   then log out and in again (or reboot)",
            details={"group": group},
        )
    if reason == PORT_BUSY:
        holders = holders_of(port)
        if holders:
            who = ", ".join(str(holder) for holder in holders)
            return Finding(
                "busy",
                f"{port} is in use by {who}",
                "stop that program (another scopelink, a planetarium, gpsd, ModemManager?) and "
                "try again",
                details={"holders": [holder.pid for holder in holders]},
            )
        return Finding(
            "busy",
            f"{port} is in use by another program (which one, /proc does not tell this user)",
            f"find it with: sudo fuser -v {port}   then stop it and try again",
        )
    return Finding("cannot-open", f"{port} will not open: {text}", "check the port's name")


def holders_of(port: str) -> list[Holder]:
    """Other processes with ``port`` open, as far as ``/proc`` shows them to this user."""
    try:
        target = os.stat(port)
    except OSError:
        return []
    found: list[Holder] = []
    proc = Path("/proc")
    if not proc.is_dir():
        return found
    for entry in proc.iterdir():
        if not entry.name.isdigit() or int(entry.name) == os.getpid():
            continue
        if _has_open(entry / "fd", target):
            found.append(Holder(int(entry.name), _process_name(entry)))
    return sorted(found, key=lambda holder: holder.pid)


def _has_open(fd_dir: Path, target: os.stat_result) -> bool:
    try:
        descriptors = list(fd_dir.iterdir())
    except OSError:  # another user's process, or it ended
        return False
    for descriptor in descriptors:
        try:
            info = os.stat(descriptor)
        except OSError:
            continue
        if (info.st_dev, info.st_ino) == (target.st_dev, target.st_ino):
            return True
    return False


def _process_name(entry: Path) -> str:
    try:
        return (entry / "comm").read_text().strip() or "?"
    except OSError:
        return "?"


def modem_manager_note() -> str | None:
    """On Linux, a warning when ModemManager is running (``systemctl is-active``), else None."""
    systemctl = shutil.which("systemctl")
    if not sys.platform.startswith("linux") or systemctl is None:
        return None
    try:
        result = subprocess.run(
            [systemctl, "is-active", "ModemManager"],
            capture_output=True,
            text=True,
            timeout=_SYSTEMCTL_TIMEOUT_S,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    if result.stdout.strip() != "active":
        return None
    return (
        "ModemManager is running: it opens new USB serial ports to look for modems (for ~30 s "
        "after plugging in) and can grab or confuse a hand control. Stop it (sudo systemctl "
        "disable --now ModemManager) or have it leave the cable alone with a udev rule, e.g. in "
        '/etc/udev/rules.d/99-scopelink.rules: ATTRS{idVendor}=="067b", '
        'ATTRS{idProduct}=="2303", ENV{ID_MM_DEVICE_IGNORE}="1" (your cable\'s ids: '
        "'scopelink ports'), then sudo udevadm control --reload"
    )


def _group_of(port: str) -> str:
    """The group that owns the port's device file; ``dialout`` when that says nothing."""
    try:
        name = grp.getgrgid(os.stat(port).st_gid).gr_name
    except (OSError, KeyError):
        return DEFAULT_GROUP
    return DEFAULT_GROUP if name in ("root", "tty") else name
