"""TargetFollower on the simulator (exact custom rates, accelerated clock): the Moon and a
comet followed to a fraction of an arcsecond, a satellite pass followed where the rates allow,
and every refusal before anything moves (issue #16)."""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from scopelink.astro import Site
from scopelink.astro.targets import (
    TargetKind,
    orbit_target,
    satellite_target,
    solar_system_target,
)
from scopelink.mount import Limits, SunAvoidanceError
from scopelink.mount.follow import FollowReport, TargetFollower
from scopelink.mount.follow_plan import FollowError
from scopelink.servers.synscan import SynScanConfig
from scopelink.sim import AZ_GTI, EQ6, SimClock, SimulatedMount
from tests.support.synscan_driver import rig
from tests.support.targets import COMETS, high_pass, iss_tle_at, site_under

T0 = datetime(2026, 3, 3, 21, tzinfo=UTC)


async def test_moon_and_a_comet_are_followed_within_an_arcsecond() -> None:
    for make in (
        lambda site: solar_system_target("Moon", site),
        lambda site: orbit_target("C/2023 A3", COMETS, site),
    ):
        site = site_under(*make(None).position(T0), T0)  # where it is high at T0
        target = make(site)
        mount = SimulatedMount(EQ6, site=site, clock=SimClock(start=T0, rate=250.0))
        await mount.connect()
        reports: list[FollowReport] = []
        follower = TargetFollower(mount, target, on_report=reports.append)
        result = await follower.run(duration_s=200.0)
        assert result.reason == "time is up"
        assert {"slewing", "following"} <= {r.phase for r in reports}
        assert result.rms_arcsec(skip_s=120.0) < 1.0, target.name  # after the goto's error
        assert mount.tracking_rates.zero  # back to zero at the end
        await mount.disconnect()


async def test_a_satellite_pass_is_met_ahead_and_followed_where_the_rates_allow(
    tmp_path: Path,
) -> None:
    site = Site(51.48, 0.0)
    iss = satellite_target("ISS", iss_tle_at(T0, tmp_path / "iss.tle"), site)
    found = high_pass(iss, T0, 30.0)
    clock = SimClock(start=found.rise - timedelta(seconds=61), rate=20.0)
    mount = SimulatedMount(EQ6, site=site, clock=clock)
    await mount.connect()
    follower = TargetFollower(mount, iss)
    plan = follower.check()
    assert plan is not None
    assert plan.rise == pytest.approx(found.rise, abs=timedelta(seconds=1))
    assert plan.peak_ra_rate_arcsec_s <= 0.9 * 3600.0
    if plan.note is not None:  # part of the pass is too fast for 1°/s: said, and skipped
        assert "needs" in plan.note
        assert "°/s in" in plan.note
    result = await follower.run(duration_s=20.0)
    settled = [e for t, e in result.errors if t > result.errors[0][0] + timedelta(seconds=5)]
    assert max(settled) < 0.25 * 3600.0
    await mount.disconnect()


async def test_refusals_come_before_anything_moves(tmp_path: Path) -> None:
    site = Site(51.48, 0.0)
    mount = SimulatedMount(EQ6, site=site, clock=SimClock.stepped(T0))
    await mount.connect()
    before = mount.state
    daytime = site_under(*solar_system_target("Sun", None).position(T0), T0)
    day = SimulatedMount(EQ6, site=daytime, clock=SimClock.stepped(T0))
    await day.connect()
    sun = solar_system_target("Sun", daytime)
    with pytest.raises(SunAvoidanceError, match=r"limits.sun_avoidance_deg = 0") as refused:
        TargetFollower(day, sun).check()
    assert "\n" not in str(refused.value)
    day.limits = Limits(sun_avoidance_deg=0.0)
    TargetFollower(day, sun).check()  # turned off explicitly: allowed
    await day.disconnect()
    mount.limits = Limits(horizon_deg=80.0)
    iss = satellite_target("ISS", iss_tle_at(T0, tmp_path / "iss.tle"), site)
    with pytest.raises(FollowError, match="ISS"):
        TargetFollower(mount, iss).check()
    assert mount.state.ra_j2000_hours == before.ra_j2000_hours
    assert mount.tracking_rates.zero
    await mount.disconnect()
    # A SynScan alt-az hand control has custom rates now (its PC loop drives the alt/az axes).
    async with rig("tcp", model=AZ_GTI, config=SynScanConfig(model=165)) as r:
        assert TargetFollower(r.mount, solar_system_target("Moon", r.mount.site)).check() is None


async def test_stop_ends_following_and_zeroes_the_rates() -> None:
    site = site_under(*solar_system_target("Jupiter", None).position(T0), T0)
    mount = SimulatedMount(EQ6, site=site, clock=SimClock(start=T0, rate=50.0))
    await mount.connect()
    stop = asyncio.Event()
    follower = TargetFollower(mount, solar_system_target("Jupiter", site), interval_s=5.0)
    task = asyncio.create_task(follower.run(stop=stop))
    await mount.wait_for(lambda s: not mount.tracking_rates.zero, timeout_s=20.0)
    stop.set()
    result = await task
    assert result.reason == "stopped"
    assert mount.tracking_rates.zero
    await mount.disconnect()


def test_the_tracking_page_states_the_followers_defaults() -> None:
    from scopelink.astro.targets.passes import SAMPLE_STEP_S
    from scopelink.mount.follow import (
        DEFAULT_INTERVAL_S,
        GAIN,
        GOTO_LEAD_S,
        INTERVAL_S,
        REPORT_EVERY_S,
    )
    from scopelink.mount.follow_plan import MIN_FOLLOW_S, PASS_WINDOW_HOURS, RATE_MARGIN
    from scopelink.web.track import PATH_MINUTES, PATH_POINTS

    docs = Path(__file__).resolve().parents[2] / "docs"
    tracking = " ".join((docs / "tracking.md").read_text(encoding="utf-8").split())
    cli = " ".join((docs / "cli.md").read_text(encoding="utf-8").split())
    assert f"`GAIN` = {GAIN:g}" in tracking
    assert f"`GOTO_LEAD_S` = {GOTO_LEAD_S:g} s" in tracking
    assert (
        f"({DEFAULT_INTERVAL_S:g} s by default, {INTERVAL_S[TargetKind.SATELLITE]:g} s" in tracking
    )
    assert f"(default {DEFAULT_INTERVAL_S:g}; {INTERVAL_S[TargetKind.SATELLITE]:g} for a" in cli
    assert f"`REPORT_EVERY_S` = {REPORT_EVERY_S:g} s" in tracking
    assert f"`RATE_MARGIN` = {RATE_MARGIN * 100:.0f} %" in tracking
    assert f"`MIN_FOLLOW_S` = {MIN_FOLLOW_S:g} s" in tracking
    assert f"within {PASS_WINDOW_HOURS:g} h" in tracking
    assert f"`SAMPLE_STEP_S` ({SAMPLE_STEP_S:g} s)" in tracking
    assert f"next {PATH_MINUTES:g} minutes in {PATH_POINTS} points" in tracking
