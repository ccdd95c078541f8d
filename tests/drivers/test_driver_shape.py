"""One driver shape (issue #13): the same ``open``, one ``timeout_s``, shared position maths, and
opening a device by its string without the CLI; the defaults match docs/architecture.md."""

from __future__ import annotations

import inspect
import subprocess
import sys
from datetime import UTC, datetime
from pathlib import Path

import pytest

from scopelink.astro import Site, j2000_to_apparent, j2000_to_observed
from scopelink.drivers import DeviceOpenError, create_mount, open_mount, parse_device
from scopelink.drivers.common import LinkStatistics, Pointing
from scopelink.drivers.open import AUTODETECT_TIMEOUT_S
from scopelink.drivers.skytracker import DEFAULT_TIMEOUT_S as SKYTRACKER_TIMEOUT_S
from scopelink.drivers.skytracker import BusOptions, SkyTrackerMount
from scopelink.drivers.skytracker.exchange import (
    DEFAULT_BUS_RETRY_DELAYS_S,
    DEFAULT_GRANT_TIMEOUT_S,
)
from scopelink.drivers.synscan import DEFAULT_TIMEOUT_S as SYNSCAN_TIMEOUT_S
from scopelink.drivers.synscan import SynScanMount

DOCS = Path(__file__).resolve().parents[2] / "docs"
SITE = Site(latitude_deg=40.4, longitude_deg=-3.7)


def _drivers_section() -> str:
    text = (DOCS / "architecture.md").read_text(encoding="utf-8")
    return text[text.index("## Drivers") :]


def test_the_documented_defaults_are_the_code_s() -> None:
    section = " ".join(_drivers_section().split())
    assert f"{SYNSCAN_TIMEOUT_S:g} s on SynScan" in section
    assert f"{SKYTRACKER_TIMEOUT_S:g} s on the Sky Tracker" in section
    delays = ", ".join(f"{d:g}" for d in DEFAULT_BUS_RETRY_DELAYS_S)
    assert (
        f"BusOptions(grant_timeout_s={DEFAULT_GRANT_TIMEOUT_S:g}, retry_delays_s=({delays}))"
        in section
    )
    assert f"with a {AUTODETECT_TIMEOUT_S:g} s reply timeout" in section
    assert BusOptions() == BusOptions(DEFAULT_GRANT_TIMEOUT_S, DEFAULT_BUS_RETRY_DELAYS_S)


def test_one_timeout_keyword_and_one_open_on_both_drivers() -> None:
    for driver, default in (
        (SynScanMount, SYNSCAN_TIMEOUT_S),
        (SkyTrackerMount, SKYTRACKER_TIMEOUT_S),
    ):
        parameter = inspect.signature(driver).parameters["timeout_s"]
        assert parameter.default == default
        assert inspect.iscoroutinefunction(driver.open), driver
        mount = driver("tcp://127.0.0.1:1", site=SITE, timeout_s=0.25)
        assert mount.timeout_s == 0.25
        assert not mount.state.connected
    assert "options" not in inspect.signature(SkyTrackerMount).parameters


async def test_the_constructors_touch_no_link() -> None:
    calls: list[str] = []

    async def factory() -> object:
        calls.append("opened")
        raise OSError("not here")

    SynScanMount(factory, site=SITE)  # type: ignore[arg-type]
    SkyTrackerMount(factory, site=SITE)  # type: ignore[arg-type]
    assert calls == []


def test_one_pointing_does_both_drivers_maths() -> None:
    read_at = datetime(2026, 11, 24, 22, 0, tzinfo=UTC)
    pointing = Pointing(5.5, 20.0, read_at, SITE, received_s=12.0)
    alt, az = j2000_to_observed(5.5, 20.0, read_at, SITE)
    ra, dec = j2000_to_apparent(5.5, 20.0, read_at)
    assert pointing.compute() == (alt, az, ra, dec)
    assert (pointing.alt_deg, pointing.az_deg) == (alt, az)
    assert (pointing.ra_of_date_hours, pointing.dec_of_date_deg) == (ra, dec)
    elsewhere = Site(latitude_deg=-33.9, longitude_deg=18.4)
    moved = pointing.at_site(elsewhere)
    assert moved.received_s == 12.0
    assert moved.alt_deg == j2000_to_observed(5.5, 20.0, read_at, elsewhere)[0]
    assert LinkStatistics().resyncs == 0


async def test_a_device_string_opens_without_the_cli() -> None:
    spec = parse_device("sim:az-gti")
    assert (spec.kind, spec.target) == ("sim", "az-gti")
    mount = create_mount(spec, site=SITE)
    assert not mount.state.connected
    opened = await open_mount("sim", SITE)
    try:
        assert opened.state.connected
    finally:
        await opened.disconnect()
    with pytest.raises(DeviceOpenError, match="no simulated mount called 'nope'"):
        parse_device("sim:nope")


def test_importing_the_drivers_loads_neither_the_cli_nor_the_simulator() -> None:
    """The CLI builds its parsers from ``scopelink.drivers.open.EXAMPLES``: importing it must not
    load numpy (the astronomy) before a command runs, nor the CLI or the simulator."""
    code = (
        "import re, sys, scopelink.drivers as d; d.parse_device('synscan:/dev/ttyUSB0'); "
        "bad = sorted(m for m in sys.modules "
        "if re.match(r'numpy|scopelink\\.(astro|cli|sim|web)', m)); "
        "print(bad)"
    )
    result = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    )
    assert result.stdout.strip() == "[]", result.stdout
