"""``scopelink ports``: the serial ports, with USB ids, likely hand-control cables flagged."""

from __future__ import annotations

import argparse
import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Final

from rich.console import Console
from rich.table import Table
from serial.tools import list_ports

from scopelink.cli.commands import CommandParsers

__all__ = ["LIKELY_ADAPTERS", "SerialPort", "find_ports", "register", "run"]

LIKELY_ADAPTERS: Final[Mapping[tuple[int, int], str]] = {
    (0x067B, 0x2303): "Prolific PL2303 USB-serial",
    (0x0403, 0x6001): "FTDI FT232R USB-serial",
    (0x1A86, 0x7523): "WCH CH340 USB-serial",
    (0x10C4, 0xEA60): "Silicon Labs CP210x USB-serial",
}
"""USB-serial chips common in hand-control and EQDIR cables, by (vendor id, product id).
A match says only that the port is such a chip; ``scopelink info`` asks what is behind it."""

_EXAMPLES = """\
examples:
  scopelink ports            every serial port; likely hand-control cables marked *
  scopelink ports --json     the same as JSON, for scripts
"""


@dataclass(frozen=True, slots=True)
class SerialPort:
    device: str
    description: str
    vid: int | None
    pid: int | None
    serial_number: str | None
    manufacturer: str | None

    @property
    def usb_id(self) -> str:
        return "" if self.vid is None or self.pid is None else f"{self.vid:04x}:{self.pid:04x}"

    @property
    def adapter(self) -> str | None:
        """What this USB id usually is, when it is a chip telescope cables use."""
        if self.vid is None or self.pid is None:
            return None
        return LIKELY_ADAPTERS.get((self.vid, self.pid))


def find_ports() -> list[SerialPort]:
    """The serial ports the OS knows of, likely hand controls first, then by name."""
    ports = [
        SerialPort(
            device=info.device,
            description=info.description if info.description != "n/a" else "",
            vid=info.vid,
            pid=info.pid,
            serial_number=info.serial_number,
            manufacturer=info.manufacturer,
        )
        for info in list_ports.comports()
    ]
    return sorted(ports, key=lambda port: (port.adapter is None, port.device))


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "ports",
        description=(
            "List the serial ports with their USB vendor:product ids. Ports on a USB-serial chip "
            "that telescope cables use (Prolific PL2303 067b:2303, FTDI 0403:6001, CH340 "
            "1a86:7523, CP210x 10c4:ea60) are marked *. Any of them may be something else: "
            "'scopelink info PORT' asks what answers."
        ),
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--json", action="store_true", help="one JSON array of ports")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    ports = find_ports()
    if args.json:
        print(json.dumps(_as_json(ports), indent=2))
        return 0
    if not ports:
        print("no serial ports found (is the cable plugged in, and its driver loaded?)")
        return 0
    Console(highlight=False).print(_table(ports))
    if any(port.adapter for port in ports):
        print("* a USB-serial chip that telescope cables use: try 'scopelink info PORT'")
    return 0


def _table(ports: Iterable[SerialPort]) -> Table:
    table = Table(show_edge=False)
    for column in ("", "port", "USB id", "description", "likely"):
        table.add_column(column)
    for port in ports:
        table.add_row(
            "*" if port.adapter else "",
            port.device,
            port.usb_id,
            port.description,
            port.adapter or "",
        )
    return table


def _as_json(ports: Iterable[SerialPort]) -> list[dict[str, object]]:
    return [
        {
            "device": port.device,
            "description": port.description,
            "usb_id": port.usb_id or None,
            "serial_number": port.serial_number,
            "manufacturer": port.manufacturer,
            "likely_hand_control": port.adapter is not None,
            "adapter": port.adapter,
        }
        for port in ports
    ]
