"""Run an emulator from a shell: ``python -m scopelink.servers.skytracker skycommander --tcp :0``.

``scopelink emulate skytracker|skycommander`` does the same through the project's CLI; this entry
point exists so a test can run (and ``kill -9``) an emulator in a process of its own.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
from collections.abc import Sequence
from pathlib import Path

from scopelink.astro import Site
from scopelink.servers.faults import Fault, FaultInjector
from scopelink.sim import SKY_TRACKER, SimClock, SimulatedMount

from .emulator import SkyCommanderEmulator, SkyTrackerEmulator

DEVICES = ("skytracker", "skycommander")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m scopelink.servers.skytracker")
    parser.add_argument("device", choices=DEVICES)
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--pty", nargs="?", const="", metavar="SYMLINK", help="serve a pty")
    where.add_argument("--tcp", metavar="HOST:PORT", help="serve TCP (port 0 picks one)")
    parser.add_argument("--data-dir", type=Path, required=True, help="non-volatile memory")
    parser.add_argument("--site", default="48.14,11.58", metavar="LAT,LON")
    parser.add_argument("--clock-rate", type=float, default=1.0, help="simulated s per real s")
    parser.add_argument("--strict-line", action="store_true", help="lose 8N1 bursts (Sky Tracker)")
    parser.add_argument("--fault", action="append", default=[], type=Fault.parse)
    return parser


async def run(args: argparse.Namespace) -> None:
    """Serve until cancelled; prints where clients connect on the first line of stdout."""
    latitude, longitude = (float(part) for part in args.site.split(","))
    mount = SimulatedMount(
        SKY_TRACKER, site=Site(latitude, longitude), clock=SimClock(rate=args.clock_rate)
    )
    faults = FaultInjector(args.fault)
    emulator: SkyTrackerEmulator | SkyCommanderEmulator
    if args.device == "skytracker":
        emulator = SkyTrackerEmulator(
            mount, args.data_dir, faults=faults, strict_line=args.strict_line
        )
    else:
        emulator = SkyCommanderEmulator(mount, args.data_dir, faults=faults)
    async with emulator:
        if args.tcp is not None:
            host, _, port = args.tcp.rpartition(":")
            server = await emulator.listen_tcp(host or "127.0.0.1", int(port))
            print(f"tcp {server.host}:{server.port}", flush=True)
        else:
            pty = await emulator.open_pty(args.pty or None)
            print(f"pty {pty.path}", flush=True)
        await asyncio.Event().wait()


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        asyncio.run(run(args))
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
