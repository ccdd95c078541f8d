"""``scopelink serve``: a mount, and the servers that put it into the software astronomers use.

With no device given (flag or config file), the mount is the built-in simulator, so the command
runs on a bare machine. Every server listens on 127.0.0.1 unless ``--host`` (or the config's
``servers.host``) says otherwise; exposing the mount beyond this machine is logged as a warning.
Ports come from the config file's ``[servers]`` table, flags override it; 0 picks a free port
and -1 turns a server off.
"""

from __future__ import annotations

import argparse
import asyncio
import dataclasses
import errno
import io
import logging
import socket
from contextlib import AsyncExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import segno

from scopelink.cli.commands import CommandParsers
from scopelink.cli.config import DEFAULT_SERVER_PORTS, ServersConfig, config_path
from scopelink.cli.errors import CommandError
from scopelink.cli.mount_session import (
    DeviceCommand,
    long_session_loop,
    mount_error,
    open_device,
    read_config,
)
from scopelink.cli.options import add_device_arguments
from scopelink.cli.serve_registry import register_serve, unregister_serve
from scopelink.cli.site_store import SettingsSiteStore
from scopelink.cli.stopping import until_stopped
from scopelink.decode import Protocol
from scopelink.links import EventLoopChoice, LinkError, describe_loop
from scopelink.links.trace import trace_logger
from scopelink.mount import AlignmentMode, Mount, MountError
from scopelink.mount.memory import DeviceMemory
from scopelink.mount.pointing import device_key
from scopelink.protocol.lx200 import SKYFI_PORT
from scopelink.servers.access import DEFAULT_POLICY, AccessPolicy, IPNetwork, parse_network
from scopelink.servers.alpaca import DISCOVERY_PORT, AlpacaServer
from scopelink.servers.alpaca.server import StateDirError
from scopelink.servers.hosts import bound_beyond_loopback, local_networks
from scopelink.servers.lx200 import LX200Server
from scopelink.servers.stellarium import Equinox, StellariumServer
from scopelink.servers.synscan import Quirks, SynScanConfig, SynScanEmulator
from scopelink.sim import PRESETS, SimulatedMount
from scopelink.web import Dashboard, protocol_by_port

__all__ = ["DEFAULT_DASHBOARD_PORT", "DEFAULT_SYNSCAN_PORT", "register", "run"]

DEFAULT_SYNSCAN_PORT = DEFAULT_SERVER_PORTS["synscan"]
"""Sky-Watcher's own SynScan network port number, so users recognise it."""
DEFAULT_DASHBOARD_PORT = 8080

_log = logging.getLogger(__name__)
_Limit = TypeVar("_Limit", int, float)

_EXAMPLES = """\
examples:
  scopelink serve                          simulated EQ6: Alpaca, LX200, Stellarium, SynScan
                                           and the dashboard on 127.0.0.1
  scopelink serve --device synscan:/dev/ttyUSB0 --site 40.4,-3.7
  scopelink serve --device skytracker:/dev/ttyUSB0 --lx200-pty /tmp/lx200
  scopelink serve --device sim:az-gti --alpaca-port 0 --synscan-port -1
  scopelink serve --host 0.0.0.0          reachable from the LAN (logged as a warning)
  scopelink serve --host 0.0.0.0 --allow 192.168.1.0/24 --read-only
                                           the home LAN may watch, nobody may command

ports: 0 picks a free one, -1 turns that server off; defaults come from the config file
('scopelink config path'), else Alpaca 11111 (+ discovery 32227), LX200 4030 (+ SkyFi 4031),
Stellarium 10001, SynScan 11880, dashboard 8080.
"""


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "serve",
        description=(
            "Run a mount and the servers that let astronomy software drive it (ASCOM Alpaca, "
            "LX200, Stellarium, SynScan, and the web dashboard), until Ctrl-C. "
            "It prints what listens where."
        ),
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_device_arguments(parser)
    parser.add_argument(
        "--mount",
        metavar="PRESET",
        choices=sorted(PRESETS),
        help="shorthand for --device sim:PRESET (simulated mount preset, e.g. eq6, az-gti)",
    )
    net = parser.add_argument_group("servers")
    net.add_argument(
        "--host",
        help="address the servers listen on (default: the config's, else 127.0.0.1, this "
        "machine only; 0.0.0.0 exposes the mount to the network)",
    )
    _port(net, "--alpaca-port", "ASCOM Alpaca HTTP (NINA, SharpCap, KStars via INDI Alpaca)")
    _port(net, "--discovery-port", "Alpaca UDP discovery", DISCOVERY_PORT)
    _port(net, "--lx200-port", "LX200 over TCP (SkySafari, Stellarium, INDI LX200)")
    _port(net, "--skyfi-port", "SkySafari's SkyFi UDP auto-detect", SKYFI_PORT)
    _port(net, "--stellarium-port", "Stellarium's binary telescope protocol")
    _port(net, "--synscan-port", "the SynScan protocol over TCP (SkySafari, INDI, Stellarium)")
    _port(net, "--dashboard-port", "the web dashboard", DEFAULT_DASHBOARD_PORT)
    access = parser.add_argument_group("access (defaults from the config's [servers])")
    access.add_argument(
        "--read-only",
        action="store_true",
        default=None,
        help="every server shows the mount but refuses commands that would change it",
    )
    access.add_argument(
        "--allow",
        action="append",
        metavar="CIDR",
        help="admit only clients in this network (repeatable; this machine is always admitted)",
    )
    access.add_argument(
        "--alpaca-allow",
        action="append",
        metavar="CIDR",
        help="Alpaca only: admit only clients in this network (repeatable; Alpaca clients "
        "cannot log in; default: --allow, else the local subnets when --host is not loopback)",
    )
    access.add_argument(
        "--allowed-host",
        action="append",
        metavar="NAME",
        help="another name the HTTP servers answer to, e.g. the LAN's DNS name for this machine "
        "(repeatable; other names get 421: DNS rebinding)",
    )
    access.add_argument(
        "--max-connections",
        type=int,
        metavar="N",
        help=f"connections at once per server (default {DEFAULT_POLICY.max_connections})",
    )
    access.add_argument(
        "--max-client-connections",
        type=int,
        metavar="N",
        help="connections at once per server from one address (default "
        f"{DEFAULT_POLICY.max_connections_per_client})",
    )
    access.add_argument(
        "--rate-limit",
        type=float,
        metavar="PER_S",
        help="commands or requests per second per client address (default "
        f"{DEFAULT_POLICY.requests_per_s:g}; the excess waits, HTTP answers 429 with Retry-After "
        f"beyond a {DEFAULT_POLICY.max_delay_s:g} s wait)",
    )
    access.add_argument(
        "--server-rate-limit",
        type=float,
        metavar="PER_S",
        help="commands or requests per second per server from all clients (default "
        f"{DEFAULT_POLICY.server_requests_per_s:g})",
    )
    net.add_argument(
        "--lx200-pty",
        nargs="?",
        const="",
        metavar="SYMLINK",
        help="also serve LX200 on a pseudo-terminal, optionally reachable as SYMLINK",
    )
    net.add_argument(
        "--synscan-pty",
        nargs="?",
        const="",
        metavar="SYMLINK",
        help="also serve SynScan on a pseudo-terminal, optionally reachable as SYMLINK",
    )
    net.add_argument(
        "--stellarium-frame",
        choices=[frame.value.lower() for frame in Equinox],
        default="j2000",
        help="coordinates Stellarium's telescope is configured for (default j2000)",
    )
    net.add_argument(
        "--state-dir",
        type=Path,
        metavar="DIR",
        help="where the Alpaca UniqueID is kept (default $XDG_STATE_HOME/scopelink)",
    )
    parser.set_defaults(run=run)


def _port(group: argparse._ArgumentGroup, flag: str, what: str, default: int | None = None) -> None:
    shown = f"default {default}" if default is not None else "default from the config file"
    group.add_argument(flag, type=int, metavar="PORT", help=f"{what} ({shown}; -1 off)")


@dataclass(frozen=True, slots=True)
class ServePlan:
    """Every server's port after merging flags over the config file; ``None`` is off."""

    host: str
    alpaca: int | None
    discovery: int | None
    lx200: int | None
    skyfi: int | None
    stellarium: int | None
    synscan: int | None
    dashboard: int | None
    lx200_pty: str | None
    synscan_pty: str | None
    access: AccessPolicy = DEFAULT_POLICY
    alpaca_access: AccessPolicy = DEFAULT_POLICY
    """The policy with Alpaca's own allow-list (``servers.alpaca.allow``)."""
    allowed_hosts: tuple[str, ...] = ()

    def runs_nothing(self) -> bool:
        listeners = (self.alpaca, self.lx200, self.stellarium, self.synscan, self.dashboard)
        return all(port is None for port in listeners) and (
            self.lx200_pty is None and self.synscan_pty is None
        )


def _merge_port(flag: int | None, configured: int | None, name: str) -> int | None:
    if flag is None:
        return configured
    if not -1 <= flag <= 65535:
        raise CommandError(f"--{name}-port {flag} is not a port", "use 0-65535, or -1 (off)")
    return None if flag < 0 else flag


def plan_from(args: argparse.Namespace) -> tuple[DeviceCommand, ServePlan]:
    if args.mount and args.device:
        raise CommandError("give --device or --mount, not both")
    command = DeviceCommand.from_args(
        args, device=f"sim:{args.mount}" if args.mount else None, default_device="sim"
    )
    config = command.config
    servers = config.servers
    host = args.host or servers.host
    access = _access_policy(args, servers)
    plan = ServePlan(
        host=host,
        alpaca=_merge_port(args.alpaca_port, servers.alpaca, "alpaca"),
        discovery=_merge_port(args.discovery_port, DISCOVERY_PORT, "discovery"),
        lx200=_merge_port(args.lx200_port, servers.lx200, "lx200"),
        skyfi=_merge_port(args.skyfi_port, SKYFI_PORT, "skyfi"),
        stellarium=_merge_port(args.stellarium_port, servers.stellarium, "stellarium"),
        synscan=_merge_port(args.synscan_port, servers.synscan, "synscan"),
        dashboard=_merge_port(args.dashboard_port, DEFAULT_DASHBOARD_PORT, "dashboard"),
        lx200_pty=args.lx200_pty,
        synscan_pty=args.synscan_pty,
        access=access,
        alpaca_access=_alpaca_policy(args, servers, access, host),
        allowed_hosts=tuple(args.allowed_host or ()) + servers.allowed_hosts,
    )
    if plan.runs_nothing():
        raise CommandError("no server to run", "leave at least one port on (not -1) or add a pty")
    return command, plan


def _access_policy(args: argparse.Namespace, servers: ServersConfig) -> AccessPolicy:
    """Flags over the config file's [servers] access keys."""
    try:
        allow = tuple(parse_network(cidr) for cidr in args.allow) if args.allow else servers.allow
    except ValueError as error:
        raise CommandError(f"--allow: {error}") from None
    rate = _or(args.rate_limit, servers.requests_per_second)
    server_rate = _or(args.server_rate_limit, servers.server_requests_per_second)
    try:
        return AccessPolicy(
            read_only=servers.read_only if args.read_only is None else args.read_only,
            allow=allow,
            max_connections=_or(args.max_connections, servers.max_connections),
            max_connections_per_client=_or(
                args.max_client_connections, servers.max_connections_per_client
            ),
            requests_per_s=rate,
            burst=max(1, round(2 * rate)),
            server_requests_per_s=server_rate,
            server_burst=max(1, round(server_rate)),
        )
    except ValueError as error:
        raise CommandError(str(error), "limits are whole numbers >= 1, the rate > 0") from None


def _alpaca_policy(
    args: argparse.Namespace, servers: ServersConfig, policy: AccessPolicy, host: str
) -> AccessPolicy:
    """Alpaca's clients cannot authenticate: beyond loopback it admits only the local subnets
    unless told otherwise (``--alpaca-allow``, ``[servers.alpaca] allow``, or ``--allow``)."""
    try:
        flagged = tuple(parse_network(c) for c in args.alpaca_allow) if args.alpaca_allow else None
    except ValueError as error:
        raise CommandError(f"--alpaca-allow: {error}") from None
    allow: tuple[IPNetwork, ...] | None = flagged if flagged is not None else servers.alpaca_allow
    if allow is None:
        allow = policy.allow
        if not allow and bound_beyond_loopback(host):
            allow = local_networks()
    return dataclasses.replace(policy, allow=allow)


def _or(flag: _Limit | None, configured: _Limit) -> _Limit:
    return configured if flag is None else flag


def run(args: argparse.Namespace) -> int:
    command, plan = plan_from(args)
    loop = long_session_loop()
    if args.trace:
        trace_logger.setLevel(logging.DEBUG)
    with asyncio.Runner(loop_factory=loop.factory) as runner:
        return runner.run(_serve(command, plan, args, loop))


def _listen_error(host: str, error: OSError) -> tuple[str, str]:
    """What went wrong opening a server's socket, and what to do about it."""
    reason = error.strerror or str(error)
    if error.errno == errno.EADDRNOTAVAIL:
        return (
            f"cannot listen on {host}: this machine has no such address",
            "--host takes 127.0.0.1 (this machine only), 0.0.0.0 (every network) or one of "
            "this machine's own addresses ('ip addr' lists them)",
        )
    if error.errno == errno.EADDRINUSE:
        return (
            f"cannot listen on {host}: a port is already in use ({reason})",
            "is another program (or another scopelink serve) using that port? -1 turns a "
            "server off, 0 picks a free port",
        )
    if error.errno in (errno.EACCES, errno.EPERM):
        return (
            f"cannot listen on {host}: permission denied",
            "ports below 1024 need privileges: pick a port above 1024",
        )
    if isinstance(error, socket.gaierror):
        return (
            f"cannot listen on {host}: no such host name ({reason})",
            "--host takes an address such as 127.0.0.1 or 0.0.0.0, or this machine's name",
        )
    return (f"cannot listen on {host}: {reason}", "-1 turns a server off, 0 picks a free port")


def synscan_model_code(mount: Mount) -> int:
    """The ``m`` code the SynScan server reports: the preset's for a simulated mount, else the
    family clients expect for this geometry (EQ6 for equatorials, AZ-GTi for alt-az)."""
    if isinstance(mount, SimulatedMount) and mount.model.synscan_model_code is not None:
        return mount.model.synscan_model_code
    if mount.capabilities.alignment_mode is AlignmentMode.ALT_AZ:
        return 165
    return 0


def _describe(mount: Mount) -> str:
    if isinstance(mount, SimulatedMount):
        return f"simulated {mount.model.name}"
    identity = mount.identity
    firmware = f" firmware {identity.firmware}" if identity.firmware else ""
    return f"{identity.model}{firmware} on {identity.link or identity.protocol}"


START_ATTEMPTS = 3
"""How often serve tries to connect to its device before giving up."""
START_RETRY_PAUSE_S = 2.0


async def open_device_patiently(command: DeviceCommand) -> Mount:
    """The connected device, tried again after a pause when it fails to answer: a hand control
    still on its start-up screens, or a flaky link losing one of the first exchanges, should not
    leave an unattended telescope computer with nothing running."""
    for attempt in range(1, START_ATTEMPTS + 1):
        try:
            return await open_device(command)
        except CommandError as error:
            if attempt == START_ATTEMPTS:
                raise
            left = START_ATTEMPTS - attempt
            _log.warning(
                "%s; trying again in %.0f s (%d more %s)",
                error,
                START_RETRY_PAUSE_S,
                left,
                "try" if left == 1 else "tries",
            )
            await asyncio.sleep(START_RETRY_PAUSE_S)
    raise AssertionError("unreachable")


async def _serve(
    command: DeviceCommand, plan: ServePlan, args: argparse.Namespace, loop: EventLoopChoice
) -> int:
    mount = await open_device_patiently(command)
    if args.state_dir is not None and mount.park_keeper.state_dir is not None:
        mount.park_keeper.enable(args.state_dir)  # park records beside the Alpaca UniqueID
    if bound_beyond_loopback(plan.host):
        _log.warning("servers listen on %s: the mount can be driven from other machines", plan.host)
    try:
        async with until_stopped() as stop, AsyncExitStack() as stack:
            site = mount.site
            print(
                f"scopelink serve: {_describe(mount)} at "
                f"{site.latitude_deg:+.4f}°, {site.longitude_deg:+.4f}°",
                flush=True,
            )
            # The PC-side syncs of this device, kept between runs (docs/pointing.md).
            mount.keep_pointing_in(DeviceMemory(device_key(mount.identity), args.state_dir))
            # One poller for every front end: reads come from the state cache.
            await stack.enter_async_context(mount.watching())
            endpoints: dict[str, object] = {"device": str(command.device)}
            for line in await _start_servers(stack, mount, plan, args, endpoints):
                print(f"  {line}", flush=True)
            running = describe_loop(asyncio.get_running_loop(), loop.reason)
            print(f"  Event loop  {running}", flush=True)
            # Found by the command line, which then drives this mount (cli/serve_registry.py).
            stack.callback(unregister_serve, register_serve(endpoints))
            print("Ctrl-C stops.", flush=True)
            await stop.wait()
    except StateDirError as error:
        raise CommandError(str(error)) from None
    except LinkError as error:
        raise CommandError(str(error), "is another program using that port?") from None
    except OSError as error:
        raise CommandError(*_listen_error(plan.host, error)) from None
    except MountError as error:
        raise mount_error(error) from None
    finally:
        try:
            await mount.disconnect()
        except (MountError, LinkError) as error:
            _log.warning("while disconnecting: %s", error)
    return 0


async def _start_servers(
    stack: AsyncExitStack,
    mount: Mount,
    plan: ServePlan,
    args: argparse.Namespace,
    endpoints: dict[str, object],
) -> list[str]:
    """Start every planned server; the lines saying what listens where. ``endpoints`` gets
    the dashboard's address as this machine reaches it, for the command line."""
    host = plan.host
    policy = plan.access
    lines: list[str] = [f"Access      {policy.describe()}"]
    if plan.alpaca is not None:
        alpaca = AlpacaServer(
            mount,
            host=host,
            port=plan.alpaca,
            discovery_port=plan.discovery,
            state_dir=args.state_dir,
            access=plan.alpaca_access,
            allowed_hosts=plan.allowed_hosts,
        )
        await stack.enter_async_context(alpaca)
        lines.append(f"Alpaca      http://{host}:{alpaca.port}/  (telescope/0)")
        if plan.alpaca_access.allow != policy.allow:
            networks = ", ".join(str(n) for n in plan.alpaca_access.allow) or "none"
            lines.append(f"Alpaca      clients: {networks} + loopback")
        if alpaca.discovery_port is not None:
            lines.append(f"Alpaca      discovery udp {host}:{alpaca.discovery_port}")
    if plan.lx200 is not None or plan.lx200_pty is not None:
        lx200 = await stack.enter_async_context(LX200Server(mount, access=policy))
        if plan.lx200 is not None:
            bound_host, port = await lx200.on_tcp(host, plan.lx200)
            lines.append(f"LX200       tcp {bound_host}:{port}")
            if plan.skyfi is not None:
                skyfi = await lx200.on_skyfi(host, plan.skyfi)
                lines.append(f"LX200       SkyFi auto-detect udp {host}:{skyfi.port}")
        if plan.lx200_pty is not None:
            lines.append(f"LX200       pty {await lx200.on_pty(plan.lx200_pty or None)}")
    if plan.stellarium is not None:
        frame = Equinox.JNOW if args.stellarium_frame == "jnow" else Equinox.J2000
        stellarium = StellariumServer(mount, host, plan.stellarium, frame=frame, access=policy)
        await stack.enter_async_context(stellarium)
        lines.append(f"Stellarium  tcp {host}:{stellarium.port}  ({frame.value})")
    decoded: dict[int, Protocol] = {}
    if plan.synscan is not None or plan.synscan_pty is not None:
        # A bridge, not a hand control: no ~7° sync limit of its own; the Mount judges every
        # sync (limits.max_sync_deg) and keeps it on the PC if need be (docs/pointing.md).
        config = SynScanConfig(model=synscan_model_code(mount), quirks=Quirks(sync_limit_deg=None))
        # A network client is not a serial line: no 9600-baud pacing on the server side.
        # dead_man: a phone app that drops must not leave the mount slewing. No motor
        # passthrough positioning: it would move an axis past every limit check.
        emulator = SynScanEmulator(
            mount, config, wire=None, access=policy, dead_man=True, axis_passthrough=False
        )
        synscan = await stack.enter_async_context(emulator)
        if plan.synscan is not None:
            bound_host, port = await synscan.on_tcp(host, plan.synscan)
            decoded[port] = Protocol.SYNSCAN
            lines.append(f"SynScan     tcp {bound_host}:{port}")
        if plan.synscan_pty is not None:
            lines.append(f"SynScan     pty {await synscan.on_pty(plan.synscan_pty or None)}")
    if plan.dashboard is not None:
        # The traffic panel decodes the SynScan server's clients and the driver's own link;
        # LX200, Stellarium and Alpaca traffic is not a mount protocol and stays undecoded.
        try:
            driver_protocol: Protocol | None = Protocol(mount.identity.protocol)
        except ValueError:
            driver_protocol = None  # the simulator has no link of its own
        trace = protocol_by_port(decoded, driver_protocol)
        dashboard = Dashboard(
            mount,
            host,
            plan.dashboard,
            trace=trace,
            access=policy,
            allowed_hosts=plan.allowed_hosts,
            # First run: with no site saved, the page asks for one and saves it here.
            site_store=SettingsSiteStore(
                config_path(), saved=bool(args.site) or read_config().site_configured
            ),
        )
        await stack.enter_async_context(dashboard)
        lines.append(f"Dashboard   {dashboard.url}")
        endpoints["dashboard"] = local_url(host, dashboard.port)
        endpoints["pairing"] = dashboard.pairing_token
        pairing = dashboard.pairing_url
        if pairing is not None:
            lines.append(f"Dashboard   pairing link for other machines (controls): {pairing}")
            lines.extend(_qr_lines(pairing))
    return lines


def local_url(host: str, port: int) -> str:
    """An HTTP server's address as a client on this machine reaches it (loopback for a
    wildcard address: the dashboard exempts loopback from pairing)."""
    if host in ("0.0.0.0", ""):
        host = "127.0.0.1"
    elif host == "::":
        host = "::1"
    shown = f"[{host}]" if ":" in host else host
    return f"http://{shown}:{port}"


def _qr_lines(url: str) -> list[str]:
    """The pairing link as a QR code a phone can scan from the terminal (segno: half blocks)."""
    out = io.StringIO()
    segno.make(url, error="l").terminal(out=out, compact=True, border=2)
    return out.getvalue().rstrip("\n").split("\n")
