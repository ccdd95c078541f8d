"""The dashboard's meridian line: the pier side, how far past the meridian, and the time left to
the limit while tracking (issue #15 part 3; docs/meridian.md), from the JSON the page shows."""

from __future__ import annotations

import re
from pathlib import Path

from scopelink.astro import lst_hours
from scopelink.mount import Limits, TrackingMode
from scopelink.mount.meridian import meridian_status
from scopelink.sim import AZ_GTI, SimClock, SimulatedMount
from tests.support.web import SITE, START, served, sim_mount

STATIC = Path(__file__).resolve().parents[2] / "src" / "scopelink" / "web" / "static"


async def test_the_state_shows_the_time_left_to_the_west_limit_while_tracking() -> None:
    mount = sim_mount(limits=Limits(meridian_east_deg=0.0, meridian_west_deg=5.0))
    async with served(mount) as s:
        # An hour east of the meridian: the west side, 5° + 15° to go, about 80 min.
        ra = (lst_hours(mount.now(), SITE.longitude_deg) + 1.0) % 24.0
        await mount.goto_equatorial(ra, 30.0)
        await mount.wait_for_slew(timeout_s=30.0)
        _, body = await s.get("/api/state")
        meridian = body["state"]["meridian"]
        assert meridian["side"] == "west"
        assert meridian["limit_deg"] == 5.0
        status = meridian_status(mount, mount.state)
        assert status is not None
        assert status.minutes_left is not None
        assert 70.0 < meridian["minutes_left"] < 84.0  # J2000 vs of date: ~1.5 min
        assert abs(meridian["minutes_left"] - status.minutes_left) < 2.0
        found = re.fullmatch(
            r"limit in 1 h (\d\d) min \(west side, -\d+\.\d° of 5° past the meridian\)",
            meridian["text"],
        )
        assert found, meridian["text"]
        await mount.set_tracking(TrackingMode.OFF)
        _, body = await s.get("/api/state")
        assert body["state"]["meridian"]["minutes_left"] is None
        assert body["state"]["meridian"]["text"].startswith("not tracking (west side")


async def test_an_alt_az_mount_has_no_meridian_line() -> None:
    mount = SimulatedMount(AZ_GTI, site=SITE, clock=SimClock(start=START, rate=30.0))
    async with served(mount) as s:
        _, body = await s.get("/api/state")
        assert body["state"]["meridian"] is None


def test_the_page_shows_the_line() -> None:
    assert 'id="st-meridian"' in (STATIC / "index.html").read_text(encoding="utf-8")
    assert 's.meridian ? s.meridian.text : "—"' in (STATIC / "app.js").read_text(encoding="utf-8")
