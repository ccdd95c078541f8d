"""Trying to break the follower (issue #16, docs/tracking.md "Tried to break it") on the
simulator with an accelerated clock: a meridian flip mid-follow, another client's rates and
goto, an ephemeris that gives no number, and hostile intervals and durations."""

from __future__ import annotations

import asyncio
import math
import re
from datetime import UTC, datetime, timedelta
from pathlib import Path

import erfa
import numpy as np
import pytest

from scopelink.astro import Site, angular_separation_deg, gmst_hours, observed_to_j2000
from scopelink.astro._arrays import FloatArray
from scopelink.astro.targets import (
    MovingTarget,
    SatelliteTarget,
    TargetKind,
    satellite_target,
    solar_system_target,
    times_after,
)
from scopelink.mount import InvalidValueError, Limits, PierSide
from scopelink.mount.follow import CHANGED_RATES, TAKEN_OVER, TargetFollower
from scopelink.mount.follow_plan import FollowError
from scopelink.mount.sun import sun_j2000
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.alpaca import blocking
from tests.support.rates import alpaca_telescope
from tests.support.targets import SATELLITES, iss_tle_at

MADRID = Site(40.4, -3.7, elevation_m=650.0)


def _hour_angle_deg(ra_hours: float, t: datetime, site: Site) -> float:
    return ((gmst_hours(t) + site.longitude_deg / 15.0 - ra_hours) * 15.0 + 180.0) % 360.0 - 180.0


async def test_a_meridian_flip_mid_follow_sends_the_mount_nowhere_else() -> None:
    """The flip's goto crosses the sky; rates worked out from its readings (up to 0.8°/s)
    carried the mount 7.6° away from the Moon after the landing before this fix. Now the flip
    (a goto not the follower's) ends following, and the flipped mount stays on the Moon."""
    moon = solar_system_target("Moon", MADRID)
    start = datetime(2026, 3, 1, 23, 0, tzinfo=UTC)
    while _hour_angle_deg(moon.position(start)[0], start, MADRID) < -1.0:
        start += timedelta(minutes=1)
    limits = Limits(meridian_west_deg=0.5, min_track_minutes=0.0, auto_flip=True)
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock(start=start, rate=150.0), limits=limits)
    await sim.connect()
    ra, dec = observed_to_j2000(40.0, 100.0, sim.now(), MADRID)
    await sim.goto_equatorial(ra, dec)  # in the east: the tube on the west side of the pier
    assert (await sim.wait_for_slew(timeout_s=20.0)).pier_side is PierSide.WEST
    worst_after_flip = 0.0
    flipped = False

    async def watch() -> None:
        nonlocal worst_after_flip, flipped
        while True:
            state = sim.state_at(sim.elapsed())
            if state.pier_side is PierSide.EAST and not state.slewing:
                flipped = True
                assert state.ra_j2000_hours is not None
                assert state.dec_j2000_deg is not None
                ra, dec = moon.position(state.read_at)
                off = angular_separation_deg(
                    ra * 15.0, dec, state.ra_j2000_hours * 15.0, state.dec_j2000_deg
                )
                worst_after_flip = max(worst_after_flip, float(off))
            await asyncio.sleep(0.02)

    watcher = asyncio.create_task(watch())
    try:
        follower = TargetFollower(sim, moon)
        result = await follower.run(duration_s=1200.0)
        landed = sim.clock.datetime_at(sim.elapsed()) + timedelta(seconds=180)
        await sim.wait_for(lambda s: s.read_at >= landed, timeout_s=20.0)
    finally:
        watcher.cancel()
        await sim.disconnect()
    assert flipped, "the mount did not flip: the test's set-up is wrong"
    assert result.reason == TAKEN_OVER or result.reason.startswith("tracking was stopped")
    assert worst_after_flip < 0.1, f"{worst_after_flip:.2f}° off the Moon after the flip"
    assert sim.tracking_rates.zero


async def test_another_clients_rates_and_goto_end_following_and_are_kept(tmp_path: Path) -> None:
    """Rates set by another client (alpyca over Alpaca) while following used to be overwritten
    within an interval and zeroed at the end: now the later command wins, following ends and
    they are kept; another client's slew ends following too (it used to pull the mount back
    at up to 1°/s)."""
    t0 = datetime(2026, 3, 1, 23, 0, tzinfo=UTC)
    moon = solar_system_target("Moon", MADRID)
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock(start=t0, rate=50.0))
    await sim.connect()
    try:
        async with alpaca_telescope(sim, tmp_path) as telescope:
            follower = TargetFollower(sim, moon, interval_s=5.0)
            task = asyncio.create_task(follower.run(duration_s=3600.0))
            await sim.wait_for(lambda s: not sim.tracking_rates.zero, timeout_s=20.0)
            await blocking(lambda: setattr(telescope, "DeclinationRate", 12.0))
            result = await asyncio.wait_for(task, 20.0)
            assert result.reason == CHANGED_RATES
            assert sim.tracking_rates.dec_arcsec_per_s == 12.0  # the other client's, kept
            await blocking(lambda: setattr(telescope, "DeclinationRate", 0.0))
            await blocking(lambda: setattr(telescope, "RightAscensionRate", 0.0))
            assert sim.tracking_rates.zero
            follower = TargetFollower(sim, moon, interval_s=5.0)
            task = asyncio.create_task(follower.run(duration_s=3600.0))
            await sim.wait_for(lambda s: not sim.tracking_rates.zero, timeout_s=20.0)
            ra, dec = observed_to_j2000(50.0, 100.0, sim.now(), MADRID)
            await blocking(lambda: telescope.SlewToCoordinatesAsync(ra, dec))
            result = await asyncio.wait_for(task, 20.0)
            assert result.reason == TAKEN_OVER
            assert sim.tracking_rates.zero
            landed = await sim.wait_for_slew(timeout_s=20.0)
            assert landed.ra_j2000_hours is not None
            # Where the other client sent it (Alpaca's coordinates are of date: 0.3° from J2000).
            assert abs(landed.ra_j2000_hours - ra) * 15.0 < 1.0
    finally:
        await sim.disconnect()


class _FailingEphemeris(MovingTarget):
    """The Moon until ``fails_at``, then no number (an orbit PyEphem cannot carry, a bug)."""

    def __init__(self, site: Site, fails_at: datetime) -> None:
        super().__init__("Broken", TargetKind.COMET, site)
        self._moon = solar_system_target("Moon", site)
        self._fails_jd = (fails_at - datetime(1970, 1, 1, tzinfo=UTC)).total_seconds() / 86400.0

    def positions(self, jd: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
        ra, dec = self._moon.positions(jd)
        unix_days = (np.asarray(jd[0]) - 2440587.5) + np.asarray(jd[1])
        bad = unix_days >= self._fails_jd
        return np.where(bad, np.nan, ra), np.where(bad, np.nan, dec)


async def test_an_ephemeris_without_numbers_mid_follow_stops_instead_of_racing() -> None:
    """A place that is not a number made the clamp ``max(-limit, min(limit, nan))`` answer
    +3600″/s: the mount was driven at 1°/s. Now following stops, rates back to zero."""
    t0 = datetime(2026, 3, 1, 23, 0, tzinfo=UTC)
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock(start=t0, rate=100.0))
    await sim.connect()
    try:
        target = _FailingEphemeris(MADRID, t0 + timedelta(seconds=150))
        fastest = 0.0

        async def watch() -> None:
            nonlocal fastest
            while True:
                rates = sim.tracking_rates
                fastest = max(fastest, abs(rates.ra_arcsec_per_s), abs(rates.dec_arcsec_per_s))
                await asyncio.sleep(0.005)

        watcher = asyncio.create_task(watch())
        result = await TargetFollower(sim, target, interval_s=5.0).run(duration_s=3600.0)
        watcher.cancel()
    finally:
        await sim.disconnect()
    assert result.reason.startswith("no number for Broken's place"), result.reason
    assert fastest < 100.0, f"driven at {fastest:g}″/s"
    assert sim.tracking_rates.zero


async def test_hostile_intervals_and_durations_are_refused_before_anything_moves() -> None:
    t0 = datetime(2026, 3, 1, 23, 0, tzinfo=UTC)
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock.stepped(t0))
    await sim.connect()
    try:
        before = sim.state
        moon = solar_system_target("Moon", MADRID)
        for interval in (math.nan, math.inf, -1.0, 1e300):
            with pytest.raises(InvalidValueError, match="interval between rate updates"):
                TargetFollower(sim, moon, interval_s=interval)
        for duration in (math.nan, math.inf, -5.0, 1e300):
            with pytest.raises(InvalidValueError, match="duration must lie in"):
                await TargetFollower(sim, moon).run(duration_s=duration)
        assert sim.state.ra_j2000_hours == before.ra_j2000_hours
        assert sim.target is None
    finally:
        await sim.disconnect()


def _site_seeing_the_iss_cross_the_sun(
    iss: SatelliteTarget, start: datetime
) -> tuple[Site, datetime]:
    """A site from which the ISS passes in front of the Sun, and when: where the line from the
    ISS away from the Sun meets the Earth (a sphere: good to a degree or so)."""
    t = start
    for _ in range(24 * 60):
        jd1, jd2 = times_after(t, np.zeros(1))
        _, teme_km, _ = iss.tle.satrec.sgp4(float(jd1[0]), float(jd2[0]))
        satellite = np.array(teme_km)
        sun_ra, sun_dec = sun_j2000(t, Site(0.0, 0.0))
        ra, dec = math.radians(sun_ra * 15.0), math.radians(sun_dec)
        towards_sun = np.array(
            [math.cos(dec) * math.cos(ra), math.cos(dec) * math.sin(ra), math.sin(dec)]
        )
        along = float(satellite @ towards_sun)
        disc = along * along - float(satellite @ satellite) + 6371.0**2
        if disc > 0.0 and along - math.sqrt(disc) > 0.0:
            x, y, z = satellite - (along - math.sqrt(disc)) * towards_sun
            theta = float(erfa.gmst82(jd1, jd2)[0])
            east_x = math.cos(theta) * x + math.sin(theta) * y
            east_y = -math.sin(theta) * x + math.cos(theta) * y
            latitude = math.degrees(math.asin(z / math.sqrt(x * x + y * y + z * z)))
            if abs(latitude) < 55.0:
                return Site(latitude, math.degrees(math.atan2(east_y, east_x))), t
        t += timedelta(minutes=1)
    raise AssertionError("the ISS never crossed the Sun for a site below 55° of latitude")


async def test_a_daytime_satellite_pass_across_the_sun_is_followed_outside_its_zone(
    tmp_path: Path,
) -> None:
    """The pass plan judged the limits but not the Sun zone: a pass in front of the Sun was
    planned whole (the follower then stopped at the zone's edge, the guard below it)."""
    t0 = datetime(2026, 3, 3, 9, tzinfo=UTC)
    tle = iss_tle_at(t0, tmp_path / "iss.tle")
    site, crossing = _site_seeing_the_iss_cross_the_sun(
        satellite_target("ISS", tle, Site(0.0, 0.0)), t0
    )
    iss = satellite_target("ISS", tle, site)
    sun_ra, sun_dec = sun_j2000(crossing, site)
    ra, dec = iss.position(crossing)
    assert angular_separation_deg(ra * 15.0, dec, sun_ra * 15.0, sun_dec) < 5.0
    sim = SimulatedMount(EQ6, site=site, clock=SimClock.stepped(crossing - timedelta(minutes=12)))
    await sim.connect()
    try:
        plan = TargetFollower(sim, iss).check()
    finally:
        await sim.disconnect()
    assert plan is not None
    assert plan.note is not None
    assert "of the Sun" in plan.note, plan.note
    seconds = int((plan.end - plan.start).total_seconds())
    ras, decs = iss.positions(times_after(plan.start, np.arange(0.0, seconds + 1.0)))
    apart = angular_separation_deg(ras * 15.0, decs, sun_ra * 15.0, sun_dec)
    assert float(np.min(apart)) >= 15.0, f"the plan comes {float(np.min(apart)):.1f}° from the Sun"


async def test_a_tle_far_from_its_epoch_is_refused_before_anything_moves(tmp_path: Path) -> None:
    """SGP4 carries a 2008 TLE to 2026 without an error: the follower planned a pass of a
    satellite that is not there and slewed to it. Now a TLE more than 30 days from now (either
    way) is refused, saying why."""
    t0 = datetime(2026, 3, 3, 21, tzinfo=UTC)
    site = Site(51.48, 0.0)
    sim = SimulatedMount(EQ6, site=site, clock=SimClock.stepped(t0))
    await sim.connect()
    try:
        stale = satellite_target("ISS", SATELLITES, site)  # 2008-09-20
        with pytest.raises(FollowError, match=r"is for 2008-09-20, 6373 days before now") as no:
            TargetFollower(sim, stale).check()  # what run() does first
        assert "get a recent TLE" in str(no.value)
        ahead = satellite_target("ISS", iss_tle_at(t0 + timedelta(days=40), tmp_path / "a"), site)
        with pytest.raises(FollowError, match=r"40 days after now"):
            TargetFollower(sim, ahead).check()
        fresh = satellite_target("ISS", iss_tle_at(t0 - timedelta(days=20), tmp_path / "f"), site)
        assert TargetFollower(sim, fresh).check() is not None
        assert sim.target is None  # nothing moved
    finally:
        await sim.disconnect()


class _Streak(MovingTarget):
    """A target crossing the sky at 1.6°/s of Dec from a place high in the south (an object
    a few thousand km away without a TLE: a re-entry, a test)."""

    def __init__(self, site: Site, at: datetime) -> None:
        super().__init__("Streak", TargetKind.ASTEROID, site)
        self._ra, self._dec = observed_to_j2000(50.0, 180.0, at, site)
        self._at = at

    def positions(self, jd: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
        unix_s = ((np.asarray(jd[0]) - 2440587.5) + np.asarray(jd[1])) * 86400.0
        seconds = unix_s - self._at.timestamp()
        return np.full_like(seconds, self._ra), self._dec + 1.6 * seconds


async def test_a_target_faster_than_the_mount_is_refused_not_trailed() -> None:
    """Only a satellite's pass was judged against the mount's rates: a faster target was
    followed at the clamp, falling further behind every second. Now refused before the goto."""
    t0 = datetime(2026, 3, 1, 23, 0, tzinfo=UTC)
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock.stepped(t0))
    await sim.connect()
    try:
        with pytest.raises(FollowError, match=r"Streak needs 5760″/s in Dec now; this mount's"):
            TargetFollower(sim, _Streak(MADRID, t0)).check()
        assert sim.target is None
    finally:
        await sim.disconnect()


class _LateStreak(_Streak):
    """Still until ``after`` seconds past ``at``, then the streak's 1.6°/s of Dec: a target that
    becomes faster than the mount while it is followed."""

    def __init__(self, site: Site, at: datetime, after: float) -> None:
        super().__init__(site, at)
        self._after = after

    def positions(self, jd: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
        unix_s = ((np.asarray(jd[0]) - 2440587.5) + np.asarray(jd[1])) * 86400.0
        moving = np.maximum(unix_s - self._at.timestamp() - self._after, 0.0)
        return np.full_like(moving, self._ra), self._dec + 1.6 * moving


async def test_a_target_that_becomes_faster_than_the_mount_ends_following_not_trailed() -> None:
    """The speed check ran only before the goto: a target that sped up later was trailed at
    the clamp, further behind at every update. Now the next update ends following, saying why."""
    t0 = datetime(2026, 3, 1, 23, 0, tzinfo=UTC)
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock(start=t0, rate=100.0))
    await sim.connect()
    try:
        follower = TargetFollower(sim, _LateStreak(MADRID, t0, after=120.0), interval_s=5.0)
        result = await follower.run(duration_s=1800.0)
        ended = sim.now()
    finally:
        await sim.disconnect()
    # The rate is measured over the update's own interval, so its figure depends on where the
    # update fell (5760″/s once the streak is at full speed; 5738″/s seen under load in CI):
    # what matters is that it is beyond the mount's 3600″/s, and said.
    needed = re.search(r"Streak needs (\d+)″/s in Dec now; this mount's", result.reason)
    assert needed is not None, result.reason
    assert int(needed.group(1)) > 3600, result.reason
    assert ended - t0 < timedelta(seconds=200), f"trailed until {ended:%H:%M:%S}"
    assert sim.tracking_rates.zero
