"""``scopelink serve`` with the access flags: the policy printed, applied to every server, and
bad values refused with one clear line."""

from __future__ import annotations

import asyncio
from pathlib import Path

from tests.support.access import HttpClient
from tests.support.serve import ALL_OFF, listening, run_serve, serving

DEVICE = "/api/v1/telescope/0"


async def test_read_only_serve_prints_its_policy_and_every_server_refuses_commands(
    tmp_path: Path,
) -> None:
    options = (
        "--alpaca-port=0",
        "--discovery-port=-1",
        "--lx200-port=0",
        "--skyfi-port=-1",
        "--stellarium-port=-1",
        "--synscan-port=-1",
        "--dashboard-port=0",
        "--read-only",
        "--allow",
        "192.168.7.0/24",
        "--rate-limit",
        "30",
    )
    async with serving(tmp_path, *options) as printed:
        assert "Access      read-only; clients: 192.168.7.0/24 + loopback;" in printed
        assert "30 requests/s per client" in printed
        http = await HttpClient.connect(listening(printed, "Alpaca"))
        ids = "ClientID=1&ClientTransactionID=1"
        connected = await http.request("PUT", f"{DEVICE}/connected", f"Connected=True&{ids}")
        assert connected.json()["ErrorNumber"] == 0
        slew = await http.request(
            "PUT", f"{DEVICE}/slewtoaltazasync", f"Azimuth=180&Altitude=50&{ids}"
        )
        assert slew.json()["ErrorNumber"] == 0x40B
        await http.close()
        reader, writer = await asyncio.open_connection("127.0.0.1", listening(printed, "LX200"))
        writer.write(b":Sr 10:00:00#:Sd +45*00:00#:MS#")
        async with asyncio.timeout(5):
            assert await reader.readexactly(2) == b"11"
            assert await reader.readuntil(b"#") == b"2Read-only server#"
        writer.close()
        await writer.wait_closed()
        dashboard = await HttpClient.connect(listening(printed, "Dashboard"))
        refused = await dashboard.request("POST", "/api/abort", "{}")
        assert refused.status == 403
        await dashboard.close()


def test_bad_access_options_fail_with_one_clear_line(tmp_path: Path) -> None:
    result = run_serve(tmp_path, *ALL_OFF[:-1], "--dashboard-port=0", "--allow", "10.0.0.0/99")
    assert result.returncode == 1
    first = result.stderr.splitlines()[0]
    assert first.startswith("scopelink serve: --allow: '10.0.0.0/99' is not an IP network")
    result = run_serve(tmp_path, "--max-connections", "0")
    assert result.returncode == 1
    assert "at least 1" in result.stderr
    assert "Traceback" not in result.stderr
