"""``scopelink info [DEVICE]``: what answers on a port, and what it can do."""

from __future__ import annotations

import argparse
import dataclasses
import enum
import json
from typing import Any

from scopelink.cli.commands import CommandParsers
from scopelink.cli.info_view import info_lines
from scopelink.cli.mount_session import run_on_mount
from scopelink.cli.options import add_device_arguments
from scopelink.drivers.skytracker import SkyTrackerMount
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import Capabilities, Mount

__all__ = ["register", "run"]

_EXAMPLES = """\
examples:
  scopelink info /dev/ttyUSB0                 try SynScan, then Sky Tracker
  scopelink info synscan:tcp://192.168.4.1:11880
  scopelink info skytracker:/dev/ttyUSB0      Sky Tracker version, Sky Commander present
  scopelink info sim:az-gti --json
"""


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "info",
        description=(
            "Connect, identify the device and show what it can do. A DEVICE without a kind "
            "prefix is tried as a SynScan hand control, then as a Sky Tracker."
        ),
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("target", nargs="?", metavar="DEVICE", help="the device (same as --device)")
    parser.add_argument("--json", action="store_true", help="one JSON object")
    add_device_arguments(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.target:
        args.device = args.target

    async def body(mount: Mount) -> int:
        report = describe(mount)
        if args.json:
            print(json.dumps(report, indent=2))
        else:
            lines = info_lines(report)
            width = max(len(key) for key, _ in lines)
            for key, value in lines:
                print(f"{key:<{width}}  {value}".rstrip())
        return 0

    return run_on_mount(args, body)


def _plain(value: object) -> Any:
    """JSON-ready form of driver details: enums by value, dataclasses and tuples recursed."""
    if isinstance(value, enum.Enum):
        return value.value
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, list | tuple | frozenset | set):
        items = [_plain(item) for item in value]
        return sorted(items) if isinstance(value, frozenset | set) else items
    if isinstance(value, int | float | str | bool) or value is None:
        return value
    return str(value)


def _capabilities(capabilities: Capabilities) -> dict[str, Any]:
    plain: dict[str, Any] = _plain(capabilities)
    return plain


def describe(mount: Mount) -> dict[str, Any]:
    """Who answered, what it can do, and the driver's own identification details (``info`` of
    the SynScan driver: firmware, model code, motor controller versions; the Sky Tracker
    driver's: version and whether a Sky Commander answered)."""
    identity = mount.identity
    report: dict[str, Any] = {
        "protocol": identity.protocol,
        "model": identity.model,
        "firmware": identity.firmware,
        "link": identity.link,
        "capabilities": _capabilities(mount.capabilities),
    }
    if isinstance(mount, SynScanMount) and mount.info is not None:
        report["details"] = _plain(mount.info)
    elif isinstance(mount, SkyTrackerMount):
        report["details"] = {
            "sky_tracker_version": mount.identity.firmware,
            "sky_commander_present": mount.commander_present,
            "mode": None if mount.tracker_mode is None else mount.tracker_mode.name.lower(),
        }
    report["aligned"] = mount.state.aligned
    return report
