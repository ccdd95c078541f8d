"""``scopelink config path|show|example``: where the settings file is and what it says."""

from __future__ import annotations

import argparse

from scopelink.cli.config import CONFIG_ENV_VAR, Config, config_path
from scopelink.cli.mount_session import read_config

__all__ = ["EXAMPLE_CONFIG", "register", "run"]

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

[servers]                           # what 'scopelink serve' listens on; false turns one off
host = "127.0.0.1"
alpaca = 11111
lx200 = 4030
stellarium = 10001
synscan = 11880
"""

_EXAMPLES = f"""\
examples:
  scopelink config path                        where the settings file is read from
  scopelink config show                        the settings in force (defaults filled in)
  scopelink config example > "$(scopelink config path)"   start from a commented example

{CONFIG_ENV_VAR}=/some/file.toml overrides the path.
"""


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "config",
        help="show where the settings file is and what it says",
        description="The settings file: device, site, horizon, limits and servers (TOML).",
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "action",
        choices=("path", "show", "example"),
        help="path: the file's path; show: the settings in force; example: a commented example",
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.action == "path":
        print(config_path())
    elif args.action == "example":
        print(EXAMPLE_CONFIG, end="")
    else:
        print(show(read_config()), end="")
    return 0


def _toml_value(value: object) -> str:
    if value is None:
        return "false"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return repr(value)


def show(config: Config) -> str:
    """The settings in force as TOML, with where they came from."""
    source = str(config.path) if config.path else f"{config_path()} (missing: all defaults)"
    site, limits, servers = config.site, config.limits, config.servers
    lines = [f"# from {source}"]
    if config.device:
        lines.append(f"device = {_toml_value(config.device)}")
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
        "",
        "[servers]",
        f"host = {_toml_value(servers.host)}",
    ]
    lines += [
        f"{name} = {_toml_value(getattr(servers, name))}"
        for name in ("alpaca", "lx200", "stellarium", "synscan")
    ]
    return "\n".join(lines) + "\n"
