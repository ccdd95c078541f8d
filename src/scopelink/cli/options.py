"""Options shared by several subcommands, parsed with errors that say what to type.

Imported to build a command's parser (``scopelink status --help``), so it imports nothing heavy:
no numpy, astronomy, mount or server modules (docs/cli.md, "Start-up").
"""

from __future__ import annotations

import argparse

from scopelink.cli.errors import CommandError
from scopelink.drivers.open import EXAMPLES

DEFAULT_SITE = "51.4779,-0.0015"
"""Greenwich: a neutral default until the user configures a site."""


def add_site_and_clock_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--site",
        default=DEFAULT_SITE,
        metavar="LAT,LON",
        help="site latitude and east longitude in degrees (default Greenwich)",
    )
    parser.add_argument(
        "--clock-rate", type=float, default=1.0, metavar="X", help="simulated time speed (1 = real)"
    )


def add_device_arguments(parser: argparse.ArgumentParser) -> None:
    """``--device``, ``--site``, ``--timeout``, ``--clock-rate`` and ``-v`` for a device command."""
    group = parser.add_argument_group("device")
    group.add_argument(
        "-d",
        "--device",
        metavar="DEVICE",
        help=f"what to talk to ({EXAMPLES}); default: the config file's device",
    )
    group.add_argument(
        "--site",
        metavar="LAT,LON",
        help="site latitude and east longitude in degrees (default: the config file's site, "
        "else Greenwich)",
    )
    group.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help="seconds to wait for each reply of a real device (default: the driver's, 5 s)",
    )
    group.add_argument(
        "--clock-rate",
        type=float,
        default=1.0,
        metavar="X",
        help="sim devices only: simulated time runs X times faster (1 = real time)",
    )
    group.add_argument(
        "-v",
        "--verbose",
        dest="trace",
        action="count",
        default=0,
        help="show every byte on the link (logger scopelink.links.trace) on stderr",
    )


def positive_rate(rate: float) -> float:
    if not rate > 0:
        raise CommandError(f"--clock-rate must be positive, not {rate}")
    return rate


def parse_host_port(text: str, option: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or int(port) > 65535:
        raise CommandError(f"bad {option} {text!r}", "give HOST:PORT, e.g. 127.0.0.1:0")
    return host.removeprefix("[").removesuffix("]"), int(port)
