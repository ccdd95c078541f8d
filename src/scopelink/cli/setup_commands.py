"""``scopelink time`` and ``scopelink site``: push the PC's clock and the configured site."""

from __future__ import annotations

import argparse

from scopelink.cli.commands import CommandParsers
from scopelink.cli.errors import CommandError
from scopelink.cli.mount_session import read_config, run_on_mount
from scopelink.cli.options import add_device_arguments
from scopelink.mount import Mount, utc_now

__all__ = ["register"]


def register(commands: CommandParsers) -> None:
    time_parser = commands.parser(
        "time",
        description="Send this computer's clock (UTC) to the mount. Keep the PC on NTP.",
        epilog="examples:\n  scopelink time\n",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_device_arguments(time_parser)
    time_parser.set_defaults(run=_run_time)

    site_parser = commands.parser(
        "site",
        description=(
            "Send the site (latitude, longitude) to the mount: --site if given, else the config "
            "file's [site]. Refuses to send the built-in default (Greenwich) by accident."
        ),
        epilog="examples:\n  scopelink site\n  scopelink site --site 40.4,-3.7\n",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_device_arguments(site_parser)
    site_parser.set_defaults(run=_run_site)


def _run_time(args: argparse.Namespace) -> int:
    async def body(mount: Mount) -> int:
        sent = utc_now()
        await mount.set_time(sent)
        print(f"mount clock set to {sent:%Y-%m-%d %H:%M:%S} UTC")
        return 0

    return run_on_mount(args, body)


def _run_site(args: argparse.Namespace) -> int:
    if not args.site and not read_config().site_configured:
        raise CommandError(
            "no site configured",
            "add --site LAT,LON or a [site] table with latitude and longitude to the config "
            "('scopelink config example' shows one)",
        )

    async def body(mount: Mount) -> int:
        # run_on_mount built the mount with the chosen site; the push tells the device.
        await mount.set_site(mount.site)
        site = mount.site
        if not mount.capabilities.can_set_site:
            print("this mount stores no site: scopelink uses it on the PC side only")
            return 0
        print(
            f"site set to latitude {site.latitude_deg:+.4f}°, longitude "
            f"{site.longitude_deg:+.4f}°, elevation {site.elevation_m:g} m"
        )
        return 0

    return run_on_mount(args, body)
