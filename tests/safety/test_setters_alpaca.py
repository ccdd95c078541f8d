"""Issue #11 part 7: no setter value can leave a mount unusable (docs/reliability-safety.md,
"Setters"; docs/alpaca.md).

Over raw HTTP, on every mount kind (both simulated geometries, the SynScan driver and the Sky
Tracker driver in front of their emulators): each impossible value answers 0x401 with a reason
(0x400 where the mount lacks the setter), never 0 and never 0x500, and afterwards every read still
answers and a command still works.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import AsyncExitStack, asynccontextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import aiohttp
import pytest

from scopelink.drivers.synscan.polling import PARK_TOLERANCE_DEG
from scopelink.mount import InvalidValueError, LimitError, Mount, ParkPosition
from scopelink.mount.setters import EARLIEST_UTC, LATEST_UTC
from scopelink.servers.alpaca import AlpacaServer, ErrorNumber
from scopelink.servers.alpaca.telescope import MAX_SETTLE_TIME_S
from scopelink.sim import AZ_GTI, EQ6
from tests.support.alpaca import sim_mount
from tests.support.skytracker_driver import rig as skytracker_rig
from tests.support.synscan_driver import rig as synscan_rig

API = "/api/v1/telescope/0"
KINDS = ["sim-eq6", "sim-azgti", "synscan", "skytracker"]

BAD_VALUES: list[tuple[str, str, str]] = [
    ("utcdate", "UTCDate", "9999-12-31T23:59:59Z"),
    ("utcdate", "UTCDate", "9999-12-31T23:59:59-05:00"),
    ("utcdate", "UTCDate", "0001-01-01T00:00:00Z"),
    ("utcdate", "UTCDate", "1999-12-31T23:00:00Z"),
    ("utcdate", "UTCDate", "2100-01-01T00:00:00Z"),
    ("utcdate", "UTCDate", "2026-02-30T00:00:00Z"),
    ("sitelatitude", "SiteLatitude", "91"),
    ("sitelatitude", "SiteLatitude", "nan"),
    ("sitelatitude", "SiteLatitude", "-1e400"),
    ("sitelongitude", "SiteLongitude", "-181"),
    ("sitelongitude", "SiteLongitude", "inf"),
    ("siteelevation", "SiteElevation", "10001"),
    ("siteelevation", "SiteElevation", "-301"),
    ("trackingrate", "TrackingRate", "4"),
    ("trackingrate", "TrackingRate", "17"),
    ("slewsettletime", "SlewSettleTime", "-1"),
    ("slewsettletime", "SlewSettleTime", "32767"),
    ("targetrightascension", "TargetRightAscension", "24.5"),
    ("targetdeclination", "TargetDeclination", "-90.5"),
    ("guideraterightascension", "GuideRateRightAscension", "1e9"),
    ("guideratedeclination", "GuideRateDeclination", "-1"),
    ("rightascensionrate", "RightAscensionRate", "1e9"),
    ("declinationrate", "DeclinationRate", "nan"),
    ("declinationrate", "DeclinationRate", "-1e9"),
]
EDGE_VALUES: list[tuple[str, str, str]] = [
    ("utcdate", "UTCDate", "2099-12-31T23:59:59Z"),
    ("sitelatitude", "SiteLatitude", "90"),
    ("sitelatitude", "SiteLatitude", "-90"),
    ("sitelongitude", "SiteLongitude", "-180"),
    ("siteelevation", "SiteElevation", "10000"),
    ("utcdate", "UTCDate", "2001-01-01T00:00:00Z"),
    ("slewsettletime", "SlewSettleTime", "300"),
]
"""Representable: accepted (or 0x400 where the mount lacks the setter), and the mount lives on."""
READS = [
    "altitude",
    "azimuth",
    "rightascension",
    "declination",
    "siderealtime",
    "utcdate",
    "devicestate",
    "atpark",
    "slewing",
    "tracking",
    "sitelatitude",
]


@asynccontextmanager
async def mount_of_kind(kind: str, tmp_path: Path) -> AsyncIterator[Mount]:
    async with AsyncExitStack() as stack:
        if kind == "synscan":
            yield (await stack.enter_async_context(synscan_rig("tcp"))).mount
        elif kind == "skytracker":
            yield (await stack.enter_async_context(skytracker_rig(tmp_path, "tcp"))).driver
        else:
            mount = sim_mount(EQ6 if kind == "sim-eq6" else AZ_GTI)
            await mount.connect()
            yield mount
            await mount.disconnect()


@asynccontextmanager
async def alpaca(kind: str, tmp_path: Path) -> AsyncIterator[aiohttp.ClientSession]:
    async with mount_of_kind(kind, tmp_path) as mount:
        server = AlpacaServer(
            mount, host="127.0.0.1", port=0, discovery_port=None, state_dir=tmp_path
        )
        async with server, aiohttp.ClientSession(base_url=server.url) as session:
            await put(session, "connected", "Connected", "True", expect={0})
            yield session


async def put(
    session: aiohttp.ClientSession, member: str, name: str, value: str, *, expect: set[int]
) -> dict[str, Any]:
    async with session.put(f"{API}/{member}", data={name: value}) as response:
        assert response.status == 200, await response.text()
        body: dict[str, Any] = await response.json()
    assert body["ErrorNumber"] in expect, f"{member}={value!r}: {body}"
    if body["ErrorNumber"]:
        assert body["ErrorMessage"], f"{member}={value!r} gave no reason"
    return body


async def assert_usable(session: aiohttp.ClientSession, after: str) -> None:
    for member in READS:
        async with session.get(f"{API}/{member}") as response:
            body = await response.json()
        assert body["ErrorNumber"] == 0, f"after {after}: {member} answered {body}"
    await put(session, "abortslew", "ClientID", "1", expect={0})


@pytest.mark.parametrize("kind", KINDS)
async def test_impossible_setter_values_are_refused_and_the_mount_stays_usable(
    kind: str, tmp_path: Path
) -> None:
    refused: set[int] = {ErrorNumber.INVALID_VALUE, ErrorNumber.NOT_IMPLEMENTED}
    async with alpaca(kind, tmp_path) as session:
        for member, name, value in BAD_VALUES:
            await put(session, member, name, value, expect=refused)
            await assert_usable(session, f"{name}={value}")
        for member, name, value in EDGE_VALUES:
            await put(session, member, name, value, expect={0, ErrorNumber.NOT_IMPLEMENTED})
            await assert_usable(session, f"{name}={value}")


async def test_utcdate_9999_answers_0x401_and_later_calls_still_answer(tmp_path: Path) -> None:
    """The issue's case: it answered 0, then every call 0x500 until a sane date was put."""
    async with alpaca("sim-eq6", tmp_path) as session:
        body = await put(session, "utcdate", "UTCDate", "9999-12-31T23:59:59Z", expect={0x401})
        assert "2099" in body["ErrorMessage"]
        await assert_usable(session, "UTCDate=9999-12-31T23:59:59Z")


@pytest.mark.parametrize("kind", ["synscan", "sim-eq6"])
async def test_the_mount_api_refuses_a_time_it_cannot_keep_before_the_wire(
    kind: str, tmp_path: Path
) -> None:
    async with mount_of_kind(kind, tmp_path) as mount:
        for when in (
            datetime(9999, 12, 31, tzinfo=UTC),
            datetime(1999, 12, 31, 23, tzinfo=UTC),
            datetime(2026, 1, 1),  # no zone
        ):
            with pytest.raises(InvalidValueError):
                await mount.set_time(when)
        await mount.set_time(datetime(2026, 11, 24, 21, tzinfo=UTC))
        await mount.refresh()


async def test_setpark_refuses_a_position_outside_the_limits(tmp_path: Path) -> None:
    """After a sync the mount may read below the horizon: SetPark there would drive it there at
    every Park."""
    async with alpaca("sim-azgti", tmp_path) as session:
        await put(session, "tracking", "Tracking", "False", expect={0})
        async with session.put(
            f"{API}/slewtoaltaz", data={"Azimuth": "180", "Altitude": "5"}
        ) as response:
            assert (await response.json())["ErrorNumber"] == 0
        async with session.put(
            f"{API}/synctoaltaz", data={"Azimuth": "180", "Altitude": "-3"}
        ) as response:
            assert (await response.json())["ErrorNumber"] == 0
        body = await put(session, "setpark", "ClientID", "1", expect={0x401})
        assert "park position" in body["ErrorMessage"]
        await assert_usable(session, "SetPark below the horizon")


def test_the_park_position_setter_checks_ranges_and_limits() -> None:
    mount = sim_mount()
    for alt, az in ((float("nan"), 0.0), (95.0, 0.0), (30.0, 360.0), (30.0, -1.0)):
        with pytest.raises(InvalidValueError):
            mount.park_position = ParkPosition(alt, az)
    with pytest.raises(LimitError, match="park position"):
        mount.park_position = ParkPosition(-5.0, 0.0)
    mount.park_position = ParkPosition(30.0, 90.0)
    assert mount.park_position == ParkPosition(30.0, 90.0)


def test_the_docs_give_the_ranges_the_code_uses() -> None:
    docs = Path(__file__).parents[2] / "docs"
    safety = (docs / "reliability-safety.md").read_text(encoding="utf-8")
    alpaca_md = (docs / "alpaca.md").read_text(encoding="utf-8")
    span = f"{EARLIEST_UTC:%Y-%m-%d} to {LATEST_UTC:%Y-%m-%dT%H:%M:%S} UTC"
    assert span in safety
    assert f"{EARLIEST_UTC:%Y-%m-%d}..{LATEST_UTC:%Y-%m-%d} UTC" in alpaca_md
    assert f"| SlewSettleTime | conn. | 0..{MAX_SETTLE_TIME_S} s |" in alpaca_md
    assert f"| Alpaca `SlewSettleTime` | 0..{MAX_SETTLE_TIME_S} s |" in safety
    assert f"`PARK_TOLERANCE_DEG` ({PARK_TOLERANCE_DEG:g}°)" in safety
