"""Issue #15 part 1 from the outside: a misaligned emulated hand control (``scopelink emulate
synscan --misalign``) behind ``scopelink serve``; syncs through Alpaca and LX200 are kept on the
PC and correct every reading; ``scopelink pointing`` lists them with residuals, removes one and
clears them, and a restarted serve finds them again (docs/pointing.md)."""

from __future__ import annotations

import asyncio
import json
import os
import re
import subprocess
import sys
import urllib.parse
import urllib.request
from pathlib import Path
from typing import Any

from scopelink.astro import angular_separation_deg
from scopelink.links import open_tcp
from scopelink.protocol.lx200 import parse_sexagesimal
from scopelink.protocol.synscan import Ack, GetRaDec, Position, SyncRaDec, SynScanClientConnection
from tests.support.cli import scopelink, synscan_emulator
from tests.support.serve import ALL_OFF, listening, serving
from tests.support.synscan import ask

SERVERS = (
    *ALL_OFF,
    "--alpaca-port=0",
    "--lx200-port=0",
    "--synscan-port=0",
    "--dashboard-port=0",
)


def alpaca(base: str, method: str, name: str, **form: object) -> Any:
    fields = {"ClientID": "7", "ClientTransactionID": "1", **{k: str(v) for k, v in form.items()}}
    url = f"{base}/api/v1/telescope/0/{name}"
    if method == "GET":
        request = urllib.request.Request(f"{url}?{urllib.parse.urlencode(fields)}")
    else:
        data = urllib.parse.urlencode(fields).encode()
        request = urllib.request.Request(url, data=data, method="PUT")
    with urllib.request.urlopen(request, timeout=10) as response:
        reply = json.loads(response.read())
    assert reply["ErrorNumber"] == 0, reply
    return reply.get("Value")


async def call(base: str, method: str, name: str, **form: object) -> Any:
    return await asyncio.to_thread(alpaca, base, method, name, **form)


async def slew_altaz(base: str, alt: float, az: float) -> None:
    await call(base, "PUT", "slewtoaltazasync", Altitude=alt, Azimuth=az)
    async with asyncio.timeout(30):
        while True:  # the server is another process: its Slewing is polled
            if not await call(base, "GET", "slewing"):
                return
            await asyncio.sleep(0.1)


async def lx200(port: int, *commands: bytes) -> list[bytes]:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    replies = []
    try:
        for command in commands:
            writer.write(command)
            async with asyncio.timeout(5):
                first = await reader.readexactly(1)
                if command.startswith((b":Sr", b":Sd")):
                    replies.append(first)
                else:
                    replies.append(first + (b"" if first == b"#" else await reader.readuntil(b"#")))
    finally:
        writer.close()
    return replies


def pointing(home: Path, dashboard: int, *args: str) -> tuple[int, str, str]:
    result = scopelink(
        home / "absent.toml", "pointing", *args, "--url", f"http://127.0.0.1:{dashboard}"
    )
    return result.returncode, result.stdout, result.stderr


async def test_syncs_from_alpaca_and_lx200_are_kept_listed_removed_and_restored(
    tmp_path: Path,
) -> None:
    with synscan_emulator("--clock-rate", "30", "--misalign", "1,-1,1.5,-1") as device:
        async with serving(tmp_path, "--device", device, *SERVERS) as printed:
            base = f"http://127.0.0.1:{listening(printed, 'Alpaca')}"
            dashboard = listening(printed, "Dashboard")
            await call(base, "PUT", "connected", Connected=True)
            await call(base, "PUT", "tracking", Tracking=False)
            status, out, err = await asyncio.to_thread(pointing, tmp_path, dashboard)
            assert status == 0, err
            assert "no syncs kept on the PC" in out

            # Alpaca: 8° off, beyond the hand control's ~7°: kept on the PC all the same.
            await slew_altaz(base, 40.0, 200.0)
            await call(base, "PUT", "synctoaltaz", Altitude=45.0, Azimuth=205.0)
            alt = await call(base, "GET", "altitude")
            az = await call(base, "GET", "azimuth")
            assert angular_separation_deg(az, alt, 205.0, 45.0) < 0.05

            # LX200 :CM# somewhere else, 2° north of where it now reads.
            port = listening(printed, "LX200")
            await slew_altaz(base, 50.0, 120.0)
            ra_text, dec_text = await lx200(port, b":GR#", b":GD#")  # degree byte 0xDF
            ra = parse_sexagesimal(ra_text[:-1].decode("latin-1"))
            dec = parse_sexagesimal(dec_text[:-1].decode("latin-1"))
            assert ra is not None
            assert dec is not None
            target_dec = dec + 2.0
            d = abs(target_dec)
            sd = f"+{int(d):02d}*{int(d * 60) % 60:02d}:{int(d * 3600) % 60:02d}"
            sr = ra_text[:-1].decode("latin-1")
            replies = await lx200(port, f":Sr {sr}#".encode(), f":Sd {sd}#".encode(), b":CM#")
            assert replies[:2] == [b"1", b"1"], replies
            (now_dec_text,) = await lx200(port, b":GD#")
            now_dec = parse_sexagesimal(now_dec_text[:-1].decode("latin-1"))
            assert now_dec is not None
            assert abs(now_dec - target_dec) < 0.05

            status, out, err = await asyncio.to_thread(pointing, tmp_path, dashboard, "--json")
            assert status == 0, err
            summary = json.loads(out)
            assert [s["number"] for s in summary["syncs"]] == [1, 2]
            assert all(s["residual_arcmin"] >= 0.0 for s in summary["syncs"])
            status, out, err = await asyncio.to_thread(pointing, tmp_path, dashboard)
            assert re.search(r"2 sync\(s\) kept on the PC; RMS \d+\.\d\d′", out), out
            status, out, err = await asyncio.to_thread(pointing, tmp_path, dashboard, "remove", "1")
            assert status == 0, err
            assert "1 sync(s) kept" in out
            status, out, err = await asyncio.to_thread(pointing, tmp_path, dashboard, "remove", "5")
            assert status != 0
            assert "there is no sync 5" in err
            assert "Traceback" not in err

        # The same device in a new serve: the sync is back.
        async with serving(tmp_path, "--device", device, *SERVERS) as printed:
            dashboard = listening(printed, "Dashboard")
            status, out, err = await asyncio.to_thread(pointing, tmp_path, dashboard)
            assert "1 sync(s) kept" in out, (out, err)
            status, out, err = await asyncio.to_thread(pointing, tmp_path, dashboard, "clear")
            assert "no syncs kept on the PC" in out

            # The SynScan server's 's', 8° from the reading: serve is a bridge, not a hand control
            # with a ~7° limit of its own.
            async with await open_tcp("127.0.0.1", listening(printed, "SynScan")) as link:
                client = SynScanClientConnection()
                here = await ask(link, client, GetRaDec(precise=True))
                assert isinstance(here, Position)
                target = (here.ra_hours, here.dec_degrees - 8.0)
                sync = SyncRaDec.from_hours_degrees(*target, precise=True)
                assert isinstance(await ask(link, client, sync), Ack)
                now = await ask(link, client, GetRaDec(precise=True))
                assert isinstance(now, Position)
                assert abs(now.dec_degrees - target[1]) < 0.05
            status, out, err = await asyncio.to_thread(pointing, tmp_path, dashboard)
            assert "1 sync(s) kept" in out, (out, err)

    status, out, err = await asyncio.to_thread(pointing, tmp_path, 1)
    assert status != 0
    assert "no scopelink dashboard answers" in err
    assert "Traceback" not in err


def run_cli(home: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """``scopelink ARGS`` with a scratch state directory (where the syncs are kept)."""
    env = {
        **os.environ,
        "SCOPELINK_CONFIG": str(home / "absent.toml"),
        "XDG_STATE_HOME": str(home / "state"),
    }
    return subprocess.run(
        [sys.executable, "-m", "scopelink", *args],
        env=env,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=60,
        check=False,
    )


def test_scopelink_sync_is_kept_for_the_next_commands(tmp_path: Path) -> None:
    """A one-shot 'scopelink sync' on a SynScan mount keeps the sync on the PC, for this device,
    so that the next 'scopelink status' reads through it (the hand control was not told)."""
    with synscan_emulator("--misalign", "0.5,0.5,0,0") as device:
        before = run_cli(tmp_path, "status", "--json", "--device", device)
        assert before.returncode == 0, before.stderr
        assert json.loads(before.stdout)["dec_j2000_deg"] > 89.5  # the hand control's home
        synced = run_cli(tmp_path, "sync", "Polaris", "--device", device)
        assert synced.returncode == 0, synced.stderr
        after = run_cli(tmp_path, "status", "--json", "--device", device)
        assert after.returncode == 0, after.stderr
        assert abs(json.loads(after.stdout)["dec_j2000_deg"] - 89.264) < 0.02
        listed = list(
            (tmp_path / "state" / "scopelink" / "devices").glob("synscan-*/pointing.json")
        )
        assert len(listed) == 1
