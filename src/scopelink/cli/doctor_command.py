"""``scopelink doctor [PORT]``: what is on a port, in words, and what to do (docs/cli.md)."""

from __future__ import annotations

import argparse
import asyncio
import json
from typing import TYPE_CHECKING

from scopelink.cli.commands import CommandParsers
from scopelink.cli.errors import CommandError

if TYPE_CHECKING:
    from scopelink.cli.doctor_probe import Finding

__all__ = ["examine", "register", "run"]

_EXAMPLES = """\
examples:
  scopelink doctor                 every serial port found (as 'scopelink ports' lists them)
  scopelink doctor /dev/ttyUSB0    one port
  scopelink doctor tcp://192.168.4.1:11880 --json
"""


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "doctor",
        description=(
            "Try what answers on a port and say what it is and what to do: a SynScan hand "
            "control (firmware, model, aligned, PC-Direct mode), a SynScan motor controller, a "
            "Sky Tracker with or without its Sky Commander, a Sky Commander alone, a Celestron "
            "NexStar, nothing, a wrong line speed; or why the port will not open. Only "
            "read-only questions are sent (versions, model, status, position): nothing moves "
            "and no setting changes. Exit status 0 when something scopelink drives answered."
        ),
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "port", nargs="?", metavar="PORT", help="a serial port or LINK (default: every port)"
    )
    parser.add_argument("--json", action="store_true", help="one JSON object per port")
    parser.add_argument(
        "--wait",
        type=float,
        default=None,
        metavar="S",
        help="how long each question waits for an answer (default 1 s)",
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from scopelink.cli.doctor_port import modem_manager_note  # noqa: PLC0415 - only to run
    from scopelink.cli.doctor_probe import FIRST_BYTE_WAIT_S  # noqa: PLC0415
    from scopelink.cli.ports_command import find_ports  # noqa: PLC0415

    wait_s = FIRST_BYTE_WAIT_S if args.wait is None else args.wait
    if not 0.05 <= wait_s <= 10.0:
        raise CommandError(f"--wait {wait_s:g} is out of range", "give 0.05 to 10 seconds")
    ports = [args.port] if args.port else [port.device for port in find_ports()]
    if not ports:
        raise CommandError(
            "no serial ports found",
            "plug the cable in (is its driver loaded? 'dmesg' says), or name a PORT",
        )
    findings = asyncio.run(_examine_all(ports, wait_s))
    note = modem_manager_note() if any("://" not in port for port in ports) else None
    for port, finding in zip(ports, findings, strict=True):
        if args.json:
            print(json.dumps(_as_json(port, finding, note)))
        else:
            print(port)
            print(f"  found: {finding.what}")
            print(f"  do:    {finding.advice}")
    if note and not args.json:
        print(f"note: {note}")
    return 0 if any(finding.usable for finding in findings) else 1


async def _examine_all(ports: list[str], wait_s: float) -> list[Finding]:
    return list(await asyncio.gather(*(examine(port, wait_s) for port in ports)))


async def examine(port: str, wait_s: float) -> Finding:
    """Open ``port`` (9600 8N1, exclusively) and probe it; or say why it will not open."""
    from scopelink.cli.doctor_port import open_failure  # noqa: PLC0415 - only to run
    from scopelink.cli.doctor_probe import probe  # noqa: PLC0415
    from scopelink.links import LinkError, open_link  # noqa: PLC0415

    try:
        link = await open_link(port)
    except LinkError as error:
        return open_failure(port, error)
    try:
        return await probe(link, port, wait_s)
    except LinkError as error:
        return open_failure(port, error)
    finally:
        await link.close()


def _as_json(port: str, finding: Finding, note: str | None) -> dict[str, object]:
    return {
        "port": port,
        "kind": finding.kind,
        "found": finding.what,
        "do": finding.advice,
        "usable": finding.usable,
        "device": finding.device,
        "details": finding.details,
        "modem_manager": note,
    }
