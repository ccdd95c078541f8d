"""``scopelink config path|show|example|init|set|unset``: the settings file, read and changed."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Final

from scopelink.cli.commands import CommandParsers
from scopelink.cli.config import CONFIG_ENV_VAR, Config, ConfigError, config_path
from scopelink.cli.config_changes import change_lines, read_settings, toml_value
from scopelink.cli.config_edit import create_config, set_values, unset_keys
from scopelink.cli.errors import CommandError
from scopelink.cli.mount_session import read_config

__all__ = ["EXAMPLE_CONFIG", "commented_out", "register", "run"]

EXAMPLE_CONFIG = """\
# scopelink settings (TOML). Command-line flags override what is here.
device = "synscan:/dev/ttyUSB0"     # or "sim", "sim:az-gti", "synscan:tcp://192.168.4.1:11880",
                                    # "skytracker:/dev/ttyUSB0", or a bare port to autodetect

[site]
latitude = 40.4                     # degrees, north positive
longitude = -3.7                    # degrees, east positive
elevation = 650                     # metres (optional)

[horizon]
altitude = 10                       # nothing moves the mount below this (degrees)
profile = [[0, 15], [90, 25], [200, 12]]   # optional [azimuth, altitude] points, interpolated

[limits]
max_altitude = 88                   # keeps alt-az mounts out of the zenith
# sun_avoidance_deg = 15            # no goto or motion within this of the Sun (0: off)
# meridian_west_deg = 5             # German mounts: tracking stops this far past the meridian
# meridian_east_deg = 5             # ... and a goto points at most this far east of it, flipped
# min_track_minutes = 10            # a goto picks the pier side that tracks at least this long
# auto_flip = false                 # at the limit, flip (goto the same target) instead of stopping

[servers]                           # what 'scopelink serve' listens on; false turns one off
host = "127.0.0.1"
alpaca = 11111
lx200 = 4030
stellarium = 10001
synscan = 11880
# read_only = true                  # servers show the mount but refuse every command
# allow = ["192.168.1.0/24"]        # client networks admitted besides this machine
# max_connections = 64              # per server; max_connections_per_client = 16
# requests_per_second = 250         # per client address (excess waits, HTTP: 429)
# server_requests_per_second = 500  # per server, all clients together
# allowed_hosts = ["scope.lan"]     # more Host names the HTTP servers answer to (others: 421)
# To give Alpaca its own client networks, replace 'alpaca = 11111' above with a table:
# [servers.alpaca]
# port = 11111
# allow = ["192.168.1.0/24"]        # default beyond loopback: the local subnets

# [readings]
# stale_after_s = 2.0               # an older reading is not served as current (0.2-5 s)
# idle_poll_s = 1.0                 # poll period while nothing needs more (0.1-2.5 s)
# demand_hold_s = 2.0               # a client's read keeps the full poll rate this long
# max_poll_baud = 9600              # polls never move more than a line of this many baud

# [park]                            # where 'park' goes (default: the pole; docs/parking.md)
# altitude = 30                     # both or neither, inside the limits
# azimuth = 200
"""

INIT_HEADER = """\
# Written by 'scopelink config init'. Every setting is commented out, so the defaults apply
# (no site, no horizon limit beyond the defaults): uncomment and edit what is true here, or use
# 'scopelink config set KEY VALUE' (which keeps these comments).
"""


def commented_out(example: str) -> str:
    """``example`` with every setting and table header behind ``#`` (comments stay as they are),
    under :data:`INIT_HEADER`."""
    lines = [
        line if not line.strip() or line.lstrip().startswith("#") else f"# {line}"
        for line in example.splitlines()
    ]
    return INIT_HEADER + "\n".join(lines) + "\n"


_EXAMPLES = f"""\
examples:
  scopelink config path                        where the settings file is read from
  scopelink config show                        the settings in force (defaults filled in)
  scopelink config init                        write the example, commented out (no overwrite)
  scopelink config set device sim:az-gti       change one value, keeping comments and layout
  scopelink config set site.latitude 40.4 site.longitude -3.7   several at once
  scopelink config set horizon.profile "[[0, 15], [90, 25]]"    any TOML value
  scopelink config set servers.lx200 false     turn a server off
  scopelink config unset horizon.profile       back to the default
  scopelink config example                     print the commented example

{CONFIG_ENV_VAR}=/some/file.toml overrides the path.
"""

_ACTIONS: Final = {
    "path": "print the settings file's path",
    "show": "print the settings in force (defaults filled in)",
    "example": "print a commented example file",
    "init": "write the example as the settings file, every setting commented out (refuses to "
    "overwrite one)",
    "set": "set dotted KEY to VALUE (TOML value, or a bare string); several KEY VALUE pairs "
    "are written together",
    "unset": "remove dotted KEYs from the file (back to their defaults)",
}


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "config",
        description="The settings file: device, site, horizon, limits and servers (TOML). "
        "set/unset keep the file's comments and layout, check the result before writing, "
        "and write atomically.",
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "action",
        choices=tuple(_ACTIONS),
        help="; ".join(f"{name}: {text}" for name, text in _ACTIONS.items()),
    )
    parser.add_argument(
        "arguments",
        nargs="*",
        metavar="KEY [VALUE]",
        help="set: KEY VALUE [KEY VALUE ...]; unset: KEY [KEY ...] (dotted: site.latitude)",
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    action: str = args.action
    arguments: list[str] = args.arguments
    if action in ("path", "show", "example", "init") and arguments:
        raise CommandError(f"config {action} takes no arguments, got {' '.join(arguments)!r}")
    if action == "path":
        print(config_path())
    elif action == "example":
        print(EXAMPLE_CONFIG, end="")
    elif action == "show":
        print(show(read_config()), end="")
    else:
        path = config_path()
        hint = f"see 'scopelink config example' for every key; {path} is unchanged"
        try:
            if action == "init":
                create_config(path, commented_out(EXAMPLE_CONFIG))
                print(f"wrote {path}: every setting commented out, the defaults apply")
                print("  change one with e.g.: scopelink config set site.latitude 40.4")
            elif action == "set":
                if not arguments or len(arguments) % 2:
                    raise CommandError(
                        "config set needs KEY VALUE pairs", "e.g. scopelink config set device sim"
                    )
                before = read_settings(path)
                set_values(path, list(zip(arguments[::2], arguments[1::2], strict=True)))
                _confirm(arguments[::2], before, path)
            else:
                if not arguments:
                    raise CommandError("config unset needs a KEY", "e.g. config unset horizon")
                before = read_settings(path)
                unset_keys(path, arguments)
                _confirm(arguments, before, path)
        except ConfigError as error:
            if action == "init":
                hint = "change it with 'scopelink config set', or move it away first"
            raise CommandError(str(error), hint) from None
    return 0


def _confirm(keys: list[str], before: dict[str, object], path: Path) -> None:
    for line in change_lines(keys, before, read_settings(path)):
        print(line)
    print(f"(in {path})")


def show(config: Config) -> str:
    """The settings in force as TOML, with where they came from."""
    source = str(config.path) if config.path else f"{config_path()} (missing: all defaults)"
    site, limits, servers = config.site, config.limits, config.servers
    lines = [f"# from {source}"]
    if config.device:
        lines.append(f"device = {toml_value(config.device)}")
    else:
        lines.append("# device: none (give --device)")
    lines += [
        "",
        "[site]" + ("" if config.site_configured else "  # default: Greenwich"),
        f"latitude = {site.latitude_deg}",
        f"longitude = {site.longitude_deg}",
        f"elevation = {site.elevation_m}",
        "",
        "[horizon]",
        f"altitude = {limits.horizon_deg}",
        f"profile = {[list(point) for point in limits.horizon_profile]}",
        "",
        "[limits]",
        f"max_altitude = {limits.max_altitude_deg}",
        f"sun_avoidance_deg = {limits.sun_avoidance_deg}",
        f"max_sync_deg = {limits.max_sync_deg}",
        f"meridian_east_deg = {limits.meridian_east_deg}",
        f"meridian_west_deg = {limits.meridian_west_deg}",
        f"min_track_minutes = {limits.min_track_minutes}",
        f"auto_flip = {toml_value(limits.auto_flip)}",
        "",
        "[servers]",
        f"host = {toml_value(servers.host)}",
    ]
    lines += [
        f"{name} = {toml_value(getattr(servers, name))}"
        for name in ("alpaca", "lx200", "stellarium", "synscan")
    ]
    lines += [
        f"read_only = {toml_value(servers.read_only)}",
        f"allow = {[str(network) for network in servers.allow]}",
        f"max_connections = {servers.max_connections}",
        f"max_connections_per_client = {servers.max_connections_per_client}",
        f"requests_per_second = {servers.requests_per_second}",
        f"server_requests_per_second = {servers.server_requests_per_second}",
        f"allowed_hosts = {list(servers.allowed_hosts)}",
    ]
    if servers.alpaca_allow is not None:
        networks = [str(network) for network in servers.alpaca_allow]
        lines.append(f"# [servers.alpaca] allow = {networks}")
    lines += [
        "",
        "[readings]",
        f"stale_after_s = {config.stale_after_s}",
        f"idle_poll_s = {config.poll_policy.idle_poll_s}",
        f"demand_hold_s = {config.poll_policy.demand_hold_s}",
        f"max_poll_baud = {config.poll_policy.max_poll_baud}",
    ]
    if config.park is not None:
        lines += ["", "[park]", f"altitude = {config.park.alt_deg}"]
        lines.append(f"azimuth = {config.park.az_deg}")
    return "\n".join(lines) + "\n"
