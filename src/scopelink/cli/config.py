"""The user's settings file: device, site, horizon, limits and servers (TOML; docs/cli.md).

The file lives in the per-user config directory (``platformdirs.user_config_dir("scopelink")``,
file ``config.toml``); the ``SCOPELINK_CONFIG`` environment variable names another file. A missing
file means every default. Command-line flags override what the file says. A bad value is an error
naming the file, the key and what was expected, never a silent default.
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import platformdirs

from scopelink.astro import Site
from scopelink.mount import InvalidValueError, LimitError, Limits, ParkPosition
from scopelink.mount.limits import DEFAULT_MAX_SYNC_DEG, SUN_AVOIDANCE_DEG
from scopelink.mount.polling import DEFAULT_STALE_AFTER_S, PollPolicy, check_stale_after
from scopelink.mount.setters import check_park_position
from scopelink.servers.access import DEFAULT_POLICY, IPNetwork, parse_network

__all__ = [
    "CONFIG_ENV_VAR",
    "DEFAULT_SERVER_PORTS",
    "Config",
    "ConfigError",
    "ServersConfig",
    "config_path",
    "load_config",
    "parse_config",
]

CONFIG_ENV_VAR: Final = "SCOPELINK_CONFIG"

DEFAULT_SERVER_PORTS: Final[Mapping[str, int]] = {
    "alpaca": 11111,  # the ASCOM Alpaca default port
    "lx200": 4030,  # SkySafari's default for LX200 over TCP
    "stellarium": 10001,  # Stellarium's telescope-control default
    "synscan": 11880,  # Sky-Watcher's own SynScan network port
}
"""Where each server listens unless the file says otherwise (``false`` turns one off)."""

DEFAULT_SERVER_HOST: Final = "127.0.0.1"
"""Servers listen on this machine only unless the file says otherwise."""

GREENWICH: Final = Site(51.4779, -0.0015)
"""A neutral default until the user configures a site."""


class ConfigError(Exception):
    """The settings file cannot be read or holds a bad value (the message names file and key)."""


@dataclass(frozen=True, slots=True)
class ServersConfig:
    """What ``scopelink serve`` listens on: a TCP port per protocol, ``None`` for off."""

    host: str = DEFAULT_SERVER_HOST
    alpaca: int | None = DEFAULT_SERVER_PORTS["alpaca"]
    lx200: int | None = DEFAULT_SERVER_PORTS["lx200"]
    stellarium: int | None = DEFAULT_SERVER_PORTS["stellarium"]
    synscan: int | None = DEFAULT_SERVER_PORTS["synscan"]
    read_only: bool = False
    """Every server refuses commands that would change the mount (docs/serve.md)."""
    allow: tuple[IPNetwork, ...] = ()
    """Client networks admitted besides loopback; empty admits every address."""
    max_connections: int = DEFAULT_POLICY.max_connections
    max_connections_per_client: int = DEFAULT_POLICY.max_connections_per_client
    requests_per_second: float = DEFAULT_POLICY.requests_per_s
    server_requests_per_second: float = DEFAULT_POLICY.server_requests_per_s
    allowed_hosts: tuple[str, ...] = ()
    """Extra ``Host`` names the HTTP servers answer to (others get 421: DNS rebinding)."""
    alpaca_allow: tuple[IPNetwork, ...] | None = None
    """``[servers.alpaca] allow``: Alpaca's own client networks (None: ``allow``, else the
    local subnets when listening beyond loopback)."""


@dataclass(frozen=True, slots=True)
class Config:
    """Everything the settings file can say; ``path`` is where it was read from."""

    path: Path | None = None
    device: str | None = None
    site: Site = GREENWICH
    site_configured: bool = False
    """Whether the file named a site (``site`` pushes only a site the user chose)."""
    limits: Limits = field(default_factory=Limits)
    servers: ServersConfig = field(default_factory=ServersConfig)
    stale_after_s: float = DEFAULT_STALE_AFTER_S
    """``[readings] stale_after_s``: a reading older than this is not served as current."""
    poll_policy: PollPolicy = field(default_factory=PollPolicy)
    """``[readings] idle_poll_s``, ``demand_hold_s``, ``max_poll_baud``: how often the mount is
    polled (docs/mount-api.md, "The poll policy")."""
    park: ParkPosition | None = None
    """``[park] altitude, azimuth``: where ``park`` goes (None: the mount's default, the pole;
    docs/parking.md)."""


def config_path() -> Path:
    """The settings file in use: ``$SCOPELINK_CONFIG`` or the per-user config directory's."""
    override = os.environ.get(CONFIG_ENV_VAR)
    if override:
        return Path(override).expanduser()
    return Path(platformdirs.user_config_dir("scopelink")) / "config.toml"


def load_config(path: Path | None = None) -> Config:
    """Read the settings file (default :func:`config_path`); a missing file gives the defaults."""
    path = path if path is not None else config_path()
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return Config(path=None)
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{path}: cannot read: {error}") from None
    return parse_config(text, path)


def parse_config(text: str, path: Path) -> Config:
    """Check and read the text of a settings file; errors name ``path`` and the key."""
    try:
        data = tomllib.loads(text)
    except ValueError as error:  # TOMLDecodeError, or an integer of more than 4300 digits
        raise ConfigError(f"{path}: not valid TOML: {error}") from None
    except RecursionError:  # tomllib recurses once per level of nested arrays and tables
        raise ConfigError(f"{path}: not valid TOML: arrays or tables nested too deeply") from None
    return _Reader(path).config(data)


_TOP_KEYS: Final = ("device", "site", "horizon", "limits", "servers", "readings", "park")
_PARK_KEYS: Final = ("altitude", "azimuth")
_READINGS_KEYS: Final = ("stale_after_s", "idle_poll_s", "demand_hold_s", "max_poll_baud")
_SITE_ATTRIBUTES: Final = {
    "latitude": "latitude_deg",
    "longitude": "longitude_deg",
    "elevation": "elevation_m",
    "pressure": "pressure_hpa",
    "temperature": "temperature_c",
    "humidity": "relative_humidity",
}
"""Each ``[site]`` key and the :class:`~scopelink.astro.Site` field it fills."""
_SITE_KEYS: Final = tuple(_SITE_ATTRIBUTES)
_HORIZON_KEYS: Final = ("altitude", "profile")
_LIMITS_KEYS: Final = (
    "max_altitude",
    "sun_avoidance_deg",
    "max_sync_deg",
    "meridian_east_deg",
    "meridian_west_deg",
    "min_track_minutes",
    "auto_flip",
)
_MERIDIAN_KEYS: Final = ("meridian_east_deg", "meridian_west_deg", "min_track_minutes")
_ACCESS_KEYS: Final = (
    "read_only",
    "allow",
    "max_connections",
    "max_connections_per_client",
    "requests_per_second",
    "server_requests_per_second",
)
_SERVERS_KEYS: Final = ("host", *DEFAULT_SERVER_PORTS, *_ACCESS_KEYS, "allowed_hosts")
_ALPACA_TABLE_KEYS: Final = ("port", "allow")


def _finite(value: int | float) -> float | None:
    """``value`` as a finite float, or None (nan, inf, or an integer beyond any float: TOML
    integers have no size limit in tomllib)."""
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


class _Reader:
    """Reads one parsed file, naming the file and the dotted key in every error."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def error(self, key: str, problem: str) -> ConfigError:
        return ConfigError(f"{self.path}: {key}: {problem}")

    def config(self, data: dict[str, Any]) -> Config:
        self.known(data, "", _TOP_KEYS)
        device = data.get("device")
        if device is not None and not (isinstance(device, str) and device.strip()):
            raise self.error(
                "device", f"expected a device string like 'synscan:/dev/ttyUSB0', got {device!r}"
            )
        site_table = self.table(data, "site")
        site = self.site(site_table) if site_table else GREENWICH
        limits = self.limits(self.table(data, "horizon"), self.table(data, "limits"))
        return Config(
            path=self.path,
            device=device.strip() if isinstance(device, str) else None,
            site=site,
            site_configured=bool(site_table),
            limits=limits,
            servers=self.servers(self.table(data, "servers")),
            stale_after_s=self.readings(self.table(data, "readings")),
            poll_policy=self.poll_policy(self.table(data, "readings")),
            park=self.park(self.table(data, "park"), limits),
        )

    def park(self, table: dict[str, Any], limits: Limits) -> ParkPosition | None:
        """``[park]``: both keys or none, a position inside the limits (else every park would
        drive the mount out of them)."""
        self.known(table, "park.", _PARK_KEYS)
        if not table:
            return None
        alt, az = self.number(table, "altitude", "park"), self.number(table, "azimuth", "park")
        if alt is None or az is None:
            raise self.error("park", "give both altitude and azimuth (degrees)")
        try:
            position = ParkPosition(alt, az % 360.0)
            check_park_position(position, limits)
        except (InvalidValueError, LimitError) as error:
            raise self.error("park", str(error)) from None
        return position

    def readings(self, table: dict[str, Any]) -> float:
        self.known(table, "readings.", _READINGS_KEYS)
        seconds = self.number(table, "stale_after_s", "readings")
        if seconds is None:
            return DEFAULT_STALE_AFTER_S
        try:
            return check_stale_after(seconds)
        except ValueError as error:
            raise self.error("readings.stale_after_s", str(error)) from None

    def poll_policy(self, table: dict[str, Any]) -> PollPolicy:
        defaults = PollPolicy()
        values: dict[str, Any] = {}
        for key in ("idle_poll_s", "demand_hold_s", "max_poll_baud"):
            number = self.number(table, key, "readings")
            values[key] = getattr(defaults, key) if number is None else number
        baud = values["max_poll_baud"]
        if baud != int(baud):
            raise self.error("readings.max_poll_baud", f"expected a whole number, got {baud!r}")
        values["max_poll_baud"] = int(baud)
        try:
            return PollPolicy(**values)
        except ValueError as error:
            key = str(error).split(" ", 1)[0]
            raise self.error(f"readings.{key}", str(error)) from None

    def known(self, table: Mapping[str, Any], prefix: str, keys: tuple[str, ...]) -> None:
        for key in table:
            if key not in keys:
                raise self.error(f"{prefix}{key}", f"unknown key (known: {', '.join(keys)})")

    def table(self, data: Mapping[str, Any], key: str) -> dict[str, Any]:
        value = data.get(key, {})
        if not isinstance(value, dict):
            raise self.error(key, f"expected a table ([{key}]), got {type(value).__name__}")
        return value

    def number(self, table: Mapping[str, Any], key: str, prefix: str) -> float | None:
        value = table.get(key)
        if value is None:
            return None
        # bool is an int in Python; 'true' as a latitude is a mistake, not 1°.
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(f"{prefix}.{key}", f"expected a number, got {value!r}")
        number = _finite(value)
        if number is None:
            raise self.error(f"{prefix}.{key}", f"expected a finite number, got {value!r}")
        return number

    def site(self, table: dict[str, Any]) -> Site:
        self.known(table, "site.", _SITE_KEYS)
        values = {key: self.number(table, key, "site") for key in _SITE_KEYS}
        latitude, longitude = values["latitude"], values["longitude"]
        for key, value in (("latitude", latitude), ("longitude", longitude)):
            if value is None:
                raise self.error(f"site.{key}", "missing (a [site] needs latitude and longitude)")
        assert latitude is not None  # checked just above
        assert longitude is not None
        options: dict[str, float] = {}
        for key, argument in list(_SITE_ATTRIBUTES.items())[2:]:  # after latitude, longitude
            value = values[key]
            if value is not None:
                options[argument] = value
        try:
            return Site(latitude, longitude, **options)
        except ValueError as error:
            # Named as the user writes it (site.latitude), not as Site calls it (latitude_deg).
            message = str(error)
            for key, attribute in _SITE_ATTRIBUTES.items():
                if message.startswith(f"Site.{attribute} "):
                    problem = message.removeprefix(f"Site.{attribute} ")
                    raise self.error(f"site.{key}", problem) from None
            raise self.error("site", message) from None

    def limits(self, horizon: dict[str, Any], limits: dict[str, Any]) -> Limits:
        self.known(horizon, "horizon.", _HORIZON_KEYS)
        self.known(limits, "limits.", _LIMITS_KEYS)
        altitude = self.number(horizon, "altitude", "horizon")
        max_altitude = self.number(limits, "max_altitude", "limits")
        sun = self.number(limits, "sun_avoidance_deg", "limits")
        max_sync = self.number(limits, "max_sync_deg", "limits")
        profile = self.profile(horizon.get("profile", []))
        meridian: dict[str, Any] = {}
        for key in _MERIDIAN_KEYS:
            value = self.number(limits, key, "limits")
            if value is not None:
                meridian[key] = value
        auto_flip = limits.get("auto_flip", False)
        if not isinstance(auto_flip, bool):
            raise self.error("limits.auto_flip", f"expected true or false, got {auto_flip!r}")
        try:
            return Limits(
                **meridian,
                auto_flip=auto_flip,
                horizon_deg=altitude if altitude is not None else 0.0,
                max_altitude_deg=max_altitude if max_altitude is not None else 90.0,
                horizon_profile=profile,
                sun_avoidance_deg=sun if sun is not None else SUN_AVOIDANCE_DEG,
                max_sync_deg=max_sync if max_sync is not None else DEFAULT_MAX_SYNC_DEG,
            )
        except InvalidValueError as error:
            table = "horizon.profile" if "profile" in str(error) else "horizon.altitude"
            key = "limits.max_altitude" if "maximum" in str(error) else table
            key = "limits.sun_avoidance_deg" if "Sun" in str(error) else key
            key = "limits.max_sync_deg" if "max_sync_deg" in str(error) else key
            for name in _MERIDIAN_KEYS:
                key = f"limits.{name}" if f"({name})" in str(error) else key
            raise self.error(key, str(error)) from None

    def profile(self, value: object) -> tuple[tuple[float, float], ...]:
        expected = "expected a list of [azimuth, altitude] pairs in degrees"
        if not isinstance(value, list):
            raise self.error("horizon.profile", f"{expected}, got {value!r}")
        points: list[tuple[float, float]] = []
        for index, point in enumerate(value):
            if not (
                isinstance(point, list)
                and len(point) == 2
                and all(isinstance(x, int | float) and not isinstance(x, bool) for x in point)
                and all(_finite(x) is not None for x in point)
            ):
                raise self.error(f"horizon.profile[{index}]", f"{expected}, got {point!r}")
            points.append((float(point[0]), float(point[1])))
        return tuple(points)

    def servers(self, table: dict[str, Any]) -> ServersConfig:
        self.known(table, "servers.", _SERVERS_KEYS)
        host = table.get("host", DEFAULT_SERVER_HOST)
        if not (isinstance(host, str) and host):
            raise self.error("servers.host", f"expected an address like '127.0.0.1', got {host!r}")
        ports: dict[str, int | None] = {}
        alpaca_allow: tuple[IPNetwork, ...] | None = None
        for name, default in DEFAULT_SERVER_PORTS.items():
            value = table.get(name, default)
            if name == "alpaca" and isinstance(value, dict):
                # [servers.alpaca]: port = 11111, allow = ["192.168.1.0/24"]
                self.known(value, "servers.alpaca.", _ALPACA_TABLE_KEYS)
                if "allow" in value:
                    alpaca_allow = self.networks(value["allow"], "servers.alpaca.allow")
                value = value.get("port", default)
            if value is False:
                ports[name] = None
            elif isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= 65535:
                ports[name] = value
            else:
                raise self.error(
                    f"servers.{name}",
                    f"expected a TCP port 0-65535 (0 picks a free one) or false (off), "
                    f"got {value!r}",
                )
        return ServersConfig(
            host=host,
            alpaca=ports["alpaca"],
            lx200=ports["lx200"],
            stellarium=ports["stellarium"],
            synscan=ports["synscan"],
            alpaca_allow=alpaca_allow,
            allowed_hosts=self.host_names(table.get("allowed_hosts", [])),
            **self.access(table),
        )

    def networks(self, value: object, key: str) -> tuple[IPNetwork, ...]:
        if not (isinstance(value, list) and all(isinstance(item, str) for item in value)):
            raise self.error(
                key, f"expected a list of networks like ['192.168.1.0/24'], got {value!r}"
            )
        try:
            return tuple(parse_network(item) for item in value)
        except ValueError as error:
            raise self.error(key, str(error)) from None

    def host_names(self, value: object) -> tuple[str, ...]:
        if not (
            isinstance(value, list)
            and all(isinstance(item, str) and item.strip() and " " not in item for item in value)
        ):
            expected = "expected a list of host names or addresses like ['scope.lan']"
            raise self.error("servers.allowed_hosts", f"{expected}, got {value!r}")
        return tuple(item.strip() for item in value)

    def access(self, table: dict[str, Any]) -> dict[str, Any]:
        """The [servers] access keys that are present, checked."""
        values: dict[str, Any] = {}
        read_only = table.get("read_only", False)
        if not isinstance(read_only, bool):
            raise self.error("servers.read_only", f"expected true or false, got {read_only!r}")
        values["read_only"] = read_only
        allow = table.get("allow", [])
        if not (isinstance(allow, list) and all(isinstance(item, str) for item in allow)):
            expected = "expected a list of networks like ['192.168.1.0/24']"
            raise self.error("servers.allow", f"{expected}, got {allow!r}")
        try:
            values["allow"] = tuple(parse_network(item) for item in allow)
        except ValueError as error:
            raise self.error("servers.allow", str(error)) from None
        for key in ("max_connections", "max_connections_per_client"):
            if key in table:
                value = table[key]
                if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                    expected = "expected a whole number >= 1"
                    raise self.error(f"servers.{key}", f"{expected}, got {value!r}")
                values[key] = value
        for key in ("requests_per_second", "server_requests_per_second"):
            if key in table:
                rate = self.number(table, key, "servers")
                if rate is None or not rate > 0.0:
                    raise self.error(f"servers.{key}", "expected a number > 0")
                values[key] = rate
        return values
