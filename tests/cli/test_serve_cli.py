"""`scopelink serve` as a user runs it: a mount (simulated, or a real driver on an emulated
device) behind every server, each reached by its own protocol over real sockets and ptys."""

from __future__ import annotations

import asyncio
import importlib.metadata
import json
import re
import socket
import struct
import urllib.parse
import urllib.request
from datetime import UTC, datetime
from pathlib import Path

from scopelink.astro import Site, angular_separation_deg, observed_to_j2000
from scopelink.cli.config import load_config
from scopelink.links import open_serial, open_tcp
from scopelink.mount import MountAxis
from scopelink.protocol.synscan import (
    GetRaDec,
    GetVersion,
    GotoInProgress,
    GotoRaDec,
    IsAligned,
    IsGotoInProgress,
    Position,
    SynScanClientConnection,
    Version,
)
from scopelink.servers.faults import Fault, FaultInjector
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SKY_TRACKER, SimClock, SimulatedMount
from tests.support.serve import ALL_FREE, ALL_OFF, listening, run_serve, serving
from tests.support.synscan import ask

UVLOOP_VERSION = importlib.metadata.version("uvloop")


def http_get(url: str) -> tuple[int, str]:
    with urllib.request.urlopen(url, timeout=5) as response:
        return response.status, response.read().decode()


def http_put(url: str, form: dict[str, str]) -> dict[str, object]:
    data = urllib.parse.urlencode(form).encode()
    request = urllib.request.Request(url, data=data, method="PUT")
    with urllib.request.urlopen(request, timeout=10) as response:
        reply: dict[str, object] = json.loads(response.read())
        return reply


def http_post_json(url: str, body: dict[str, object]) -> dict[str, object]:
    request = urllib.request.Request(
        url, data=json.dumps(body).encode(), headers={"Content-Type": "application/json"}
    )
    with urllib.request.urlopen(request, timeout=10) as response:
        reply: dict[str, object] = json.loads(response.read())
        return reply


def connect_alpaca(device_url: str) -> None:
    """Alpaca clients connect before anything else (reads answer NotConnected before)."""
    reply = http_put(
        f"{device_url}/connected",
        {"Connected": "True", "ClientID": "1", "ClientTransactionID": "1"},
    )
    assert reply["ErrorNumber"] == 0, reply


async def test_serve_puts_the_simulated_mount_behind_every_server(tmp_path: Path) -> None:
    async with serving(tmp_path, *ALL_FREE, "--synscan-pty", "--lx200-pty") as printed:
        assert printed.startswith("scopelink serve: simulated EQ6 at +51.4779°")
        # Everything below runs on uvloop, a dependency here (docs/serve.md, "Event loop").
        assert f"\n  Event loop  uvloop {UVLOOP_VERSION}\n" in printed

        # ASCOM Alpaca: a property read and the management API
        alpaca = listening(printed, "Alpaca")
        base = f"http://127.0.0.1:{alpaca}"
        await asyncio.to_thread(connect_alpaca, f"{base}/api/v1/telescope/0")
        status, body = await asyncio.to_thread(
            http_get, f"{base}/api/v1/telescope/0/declination?ClientID=1"
        )
        assert status == 200
        reading = json.loads(body)
        assert reading["ErrorNumber"] == 0
        # Power-on: the pole of date (JNow) for a GEM
        assert 89.5 < reading["Value"] <= 90.0
        _, devices = await asyncio.to_thread(http_get, f"{base}/management/v1/configureddevices")
        assert json.loads(devices)["Value"][0]["DeviceType"] == "Telescope"
        assert (tmp_path / "state" / "scopelink").is_dir(), "UniqueID kept in the state dir"

        # Alpaca discovery answers on 127.0.0.1
        discovery = listening(printed, "Alpaca      discovery")
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.settimeout(5)
            probe.sendto(b"alpacadiscovery1", ("127.0.0.1", discovery))
            answer, _ = probe.recvfrom(1024)
        assert json.loads(answer) == {"AlpacaPort": alpaca}

        # LX200 over TCP and on a pty
        reader, writer = await asyncio.open_connection("127.0.0.1", listening(printed, "LX200"))
        writer.write(b":GD#")
        async with asyncio.timeout(5):
            dec = await reader.readuntil(b"#")
        assert re.fullmatch(rb"[+-]\d\d\xdf\d\d[:']\d\d#", dec), dec  # Meade's degree byte
        writer.close()
        lx200_pty = re.search(r"LX200 +pty (/dev/\S+)", printed)
        assert lx200_pty
        async with await open_serial(lx200_pty.group(1)) as link:
            await link.write(b"\x06")
            assert await link.read_exactly(1) == b"G"  # a German equatorial

        # Stellarium: a position message arrives unasked
        reader, writer = await asyncio.open_connection(
            "127.0.0.1", listening(printed, "Stellarium")
        )
        async with asyncio.timeout(5):
            message = await reader.readexactly(24)
        length, kind = struct.unpack_from("<HH", message)
        assert (length, kind) == (24, 0)
        writer.close()

        # SynScan over TCP and on a pty
        async with await open_tcp("127.0.0.1", listening(printed, "SynScan")) as link:
            client = SynScanClientConnection()
            version = await ask(link, client, GetVersion())
            assert isinstance(version, Version)
            assert version.as_tuple()[:2] == (4, 39)
            assert await ask(link, client, IsAligned()) is not None
            position = await ask(link, client, GetRaDec(precise=True))
            assert isinstance(position, Position)
            # J2000: precession puts the pole of date 0.1-0.2° from J2000's pole now
            assert 0.05 < 90.0 - position.dec_degrees < 0.25
        synscan_pty = re.search(r"SynScan +pty (/dev/\S+)", printed)
        assert synscan_pty
        async with await open_serial(synscan_pty.group(1)) as link:
            position = await ask(link, SynScanClientConnection(), GetRaDec(precise=False))
            assert isinstance(position, Position)

        # the dashboard, and its first-run check saving the site to the settings file
        dashboard = f"http://127.0.0.1:{listening(printed, 'Dashboard')}"
        status, page = await asyncio.to_thread(http_get, f"{dashboard}/")
        assert status == 200
        assert "<html" in page.lower()
        settings = tmp_path / "absent.toml"  # tests.support.serve: no settings file yet
        _, setup = await asyncio.to_thread(http_get, f"{dashboard}/api/setup")
        assert json.loads(setup)["needed"] is True
        site: dict[str, object] = {"latitude_deg": 40.4, "longitude_deg": -3.7}
        saved = await asyncio.to_thread(http_post_json, f"{dashboard}/api/setup", site)
        assert saved["saved_to"] == str(settings)
        assert load_config(settings).site == Site(40.4, -3.7)


SKY_SITE = Site(48.0, 11.0)


async def test_serve_puts_a_sky_tracker_behind_synscan_and_alpaca(tmp_path: Path) -> None:
    """The bridge no one else has: a Sky Tracker (+ Sky Commander) driven with the SynScan
    protocol and through ASCOM Alpaca. The box is emulated in this process on TCP; serve runs
    the real Sky Tracker driver against it."""
    sim = SimulatedMount(
        SKY_TRACKER, site=SKY_SITE, clock=SimClock(start=datetime.now(UTC), rate=1.0)
    )
    async with SkyTrackerEmulator(sim, tmp_path / "commander") as emulator:
        host, port = await emulator.on_tcp()
        # start near the target so the real-time GOTO is short
        sim.set_axis_position(MountAxis.PRIMARY, 150.0)
        sim.set_axis_position(MountAxis.SECONDARY, 40.0)
        options = (*ALL_OFF[:-1], "--synscan-port=0", "--alpaca-port=0", "--dashboard-port=-1")
        async with serving(
            tmp_path,
            "--device",
            f"skytracker:tcp://{host}:{port}",
            "--site",
            "48,11",
            *options,
        ) as printed:
            assert "Sky Tracker" in printed.splitlines()[0]
            target = observed_to_j2000(44.0, 154.0, sim.clock.now(), SKY_SITE)
            async with await open_tcp("127.0.0.1", listening(printed, "SynScan")) as link:
                client = SynScanClientConnection()
                position = await ask(link, client, GetRaDec(precise=True))
                assert isinstance(position, Position)
                here = sim.j2000_at(sim.elapsed())
                assert (
                    angular_separation_deg(
                        position.ra_hours * 15, position.dec_degrees, here[0] * 15, here[1]
                    )
                    < 0.05
                )
                await ask(link, client, GotoRaDec.from_hours_degrees(*target))
                async with asyncio.timeout(30):
                    while True:
                        busy = await ask(link, client, IsGotoInProgress())
                        assert isinstance(busy, GotoInProgress)
                        if not busy.in_progress:
                            break
                        await asyncio.sleep(0.2)
            landed = sim.j2000_at(sim.elapsed())
            miss = angular_separation_deg(landed[0] * 15, landed[1], target[0] * 15, target[1])
            assert miss < 0.05, f"the Sky Tracker landed {miss:.3f}° from the target"

            alpaca = listening(printed, "Alpaca")
            url = f"http://127.0.0.1:{alpaca}/api/v1/telescope/0"
            await asyncio.to_thread(connect_alpaca, url)
            _, body = await asyncio.to_thread(http_get, f"{url}/canslewasync")
            assert json.loads(body)["Value"] is True
            _, body = await asyncio.to_thread(http_get, f"{url}/tracking")
            assert json.loads(body)["Value"] is True, "a Sky Tracker GOTO ends in tracking"
            # A slew below the horizon is refused and nothing moves.
            below = observed_to_j2000(-10.0, 154.0, sim.clock.now(), SKY_SITE)
            reply = await asyncio.to_thread(
                http_put,
                f"{url}/slewtocoordinatesasync",
                {
                    "RightAscension": str(below[0]),
                    "Declination": str(below[1]),
                    "ClientID": "1",
                    "ClientTransactionID": "2",
                },
            )
            assert reply["ErrorNumber"] != 0
            assert "horizon" in str(reply["ErrorMessage"])
            await asyncio.sleep(0.5)
            still = sim.j2000_at(sim.elapsed())
            assert angular_separation_deg(still[0] * 15, still[1], landed[0] * 15, landed[1]) < 0.05


def test_bad_options_fail_with_one_clear_line(tmp_path: Path) -> None:
    result = run_serve(tmp_path, "--synscan-port", "70000")
    assert result.returncode == 1
    assert result.stderr.splitlines()[0] == ("scopelink serve: --synscan-port 70000 is not a port")
    result = run_serve(tmp_path, *ALL_OFF)
    assert result.returncode == 1
    assert result.stderr.splitlines()[0] == "scopelink serve: no server to run"
    result = run_serve(tmp_path, "--device", "sim:nonesuch")
    assert result.returncode == 1
    assert "no simulated mount called 'nonesuch'" in result.stderr
    assert "Traceback" not in result.stderr
    result = run_serve(tmp_path, env={"SCOPELINK_EVENT_LOOP": "libuv"})
    assert result.returncode == 1
    assert result.stderr.splitlines() == [
        "scopelink serve: SCOPELINK_EVENT_LOOP='libuv' is not one of auto, uvloop, asyncio",
        "  hint: unset it, or set it to auto, uvloop, asyncio",
    ]


def test_a_port_in_use_is_reported_with_a_hint(tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = run_serve(tmp_path, *ALL_OFF[:-2], f"--synscan-port={port}", "--dashboard-port=-1")
    assert result.returncode == 1
    assert result.stderr.startswith("scopelink serve:")
    assert "another program" in result.stderr
    assert "Traceback" not in result.stderr


async def test_serve_tries_a_device_that_fails_its_first_exchanges_again(tmp_path: Path) -> None:
    # A hand control still booting (or a flaky link) loses the first replies: serve retries
    # instead of leaving the telescope computer with nothing running.
    sim = SimulatedMount(EQ6, site=SKY_SITE, clock=SimClock(start=datetime.now(UTC), rate=1.0))
    faults = FaultInjector()
    faults.add(Fault.parse("any:drop:times=4"))
    async with SynScanEmulator(sim, faults=faults) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        options = (*ALL_OFF[:-1], "--synscan-port=0", "--dashboard-port=-1")
        device = ("--device", f"synscan:tcp://{host}:{port}", "--timeout", "0.3")
        # On asyncio's own loop, as told (the timeouts and retries work on either loop).
        env = {"SCOPELINK_EVENT_LOOP": "asyncio"}
        async with serving(tmp_path, *device, "--site", "48,11", *options, env=env) as printed:
            assert "\n  Event loop  asyncio (epoll; SCOPELINK_EVENT_LOOP=asyncio)\n" in printed
            assert "SynScan" in printed
            assert len(faults.fired) == 4  # the first attempt failed on them
            async with await open_tcp("127.0.0.1", listening(printed, "SynScan")) as link:
                position = await ask(link, SynScanClientConnection(), GetRaDec(precise=True))
                assert isinstance(position, Position)
