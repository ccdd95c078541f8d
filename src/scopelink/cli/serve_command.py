"""``scopelink serve``: a mount, and the servers that put it into the software astronomers use.

With no device given, the mount is the built-in simulator, so the command runs on a bare machine.
Servers listen on 127.0.0.1 unless ``--host`` says otherwise.
"""

from __future__ import annotations

import argparse
import asyncio
import ipaddress
import logging

from scopelink.cli.errors import CommandError
from scopelink.cli.options import (
    add_site_and_clock_arguments,
    parse_site,
    positive_rate,
    until_stopped,
)
from scopelink.links import LinkError
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import PRESETS, SimClock, SimulatedMount

__all__ = ["DEFAULT_SYNSCAN_PORT", "register", "run"]

DEFAULT_SYNSCAN_PORT = 11880
"""Sky-Watcher's own SynScan network port number, so users recognise it."""

_log = logging.getLogger(__name__)

_EXAMPLES = """\
examples:
  scopelink serve                          simulated EQ6; SynScan on 127.0.0.1:11880
  scopelink serve --mount az-gti --site 40.4,-3.7
  scopelink serve --synscan-pty /tmp/synscan   also a serial-like device for INDI or Stellarium
"""


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "serve",
        help="run a mount with its servers (the simulated mount when no device is given)",
        description=(
            "Run a mount and the servers that let astronomy software drive it, until Ctrl-C. "
            "It prints what listens where."
        ),
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--host",
        default="127.0.0.1",
        help="address the servers listen on (default 127.0.0.1, this machine only; "
        "0.0.0.0 exposes the mount to the network)",
    )
    parser.add_argument(
        "--mount",
        default="eq6",
        choices=sorted(
            name for name, model in PRESETS.items() if model.synscan_model_code is not None
        ),
        help="simulated mount preset (default eq6)",
    )
    parser.add_argument(
        "--synscan-port",
        type=int,
        default=DEFAULT_SYNSCAN_PORT,
        metavar="PORT",
        help=f"TCP port of the SynScan server (default {DEFAULT_SYNSCAN_PORT}; 0 picks a free "
        "one; -1 turns it off)",
    )
    parser.add_argument(
        "--synscan-pty",
        nargs="?",
        const="",
        metavar="SYMLINK",
        help="also serve SynScan on a pseudo-terminal, optionally reachable as SYMLINK",
    )
    add_site_and_clock_arguments(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if not -1 <= args.synscan_port <= 65535:
        raise CommandError(f"--synscan-port {args.synscan_port} is not a TCP port")
    if args.synscan_port < 0 and args.synscan_pty is None:
        raise CommandError("no server to run", "drop --synscan-port -1 or add --synscan-pty")
    return asyncio.run(_serve(args))


def _exposes_beyond_this_machine(host: str) -> bool:
    try:
        return not ipaddress.ip_address(host).is_loopback
    except ValueError:
        return host != "localhost"


async def _serve(args: argparse.Namespace) -> int:
    preset = PRESETS[args.mount]
    site = parse_site(args.site)
    clock = SimClock(rate=positive_rate(args.clock_rate))
    mount = SimulatedMount(preset, site=site, clock=clock)
    config = SynScanConfig(model=preset.synscan_model_code or 0)
    # A network client is not a serial line: no 9600-baud pacing on the server side.
    synscan = SynScanEmulator(mount, config, wire=None)
    try:
        async with until_stopped() as stop, synscan:
            print(
                f"scopelink serve: simulated {preset.name} at "
                f"{site.latitude_deg:+.4f}°, {site.longitude_deg:+.4f}°",
                flush=True,
            )
            if args.synscan_port >= 0:
                if _exposes_beyond_this_machine(args.host):
                    _log.warning("SynScan server exposed beyond this machine on %s", args.host)
                host, port = await synscan.on_tcp(args.host, args.synscan_port)
                print(f"  SynScan    tcp {host}:{port}", flush=True)
            if args.synscan_pty is not None:
                path = await synscan.on_pty(args.synscan_pty or None)
                print(f"  SynScan    pty {path}", flush=True)
            print("Ctrl-C stops.", flush=True)
            await stop.wait()
    except LinkError as error:
        raise CommandError(str(error), "is another program using that port?") from None
    except OSError as error:
        raise CommandError(f"cannot listen on {args.host}: {error}") from None
    return 0
