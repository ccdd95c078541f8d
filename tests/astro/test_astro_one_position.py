"""One float position at one datetime (a mount's poll) goes through ``astro.one_position``, in
Python floats over cached contexts; it must equal the array path (``erfa.atciqz``/``atioq``)
within a milliarcsecond, at any instant of the years a mount is used, as a poll's instants follow
one another (contexts reused, crossing midnight and a leap second), with and without refraction.
"""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta, timezone
from pathlib import Path

import numpy as np
import pytest

from scopelink.astro import Site, j2000_to_apparent, j2000_to_observed, one_position
from scopelink.astro._arrays import FloatArray
from scopelink.astro.one_position import OBSERVER_REUSE_S

MILLIARCSEC_DEG = 1e-3 / 3600.0
SITES = [
    Site(51.4779, -0.0015, 46.0),
    Site(-31.2734, 149.0664, 1165.0, temperature_c=-5.0, relative_humidity=0.9),
    Site(48.0, 11.0, pressure_hpa=0.0),
    Site(-89.99, 139.27, 2835.0, temperature_c=-55.0),
    Site(0.0, -179.9, 0.0),
]


def _array_path(
    ra: FloatArray, dec: FloatArray, when: datetime, site: Site, dut1: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The vector path: all positions at once (``tests/astro/test_astro_fast_path.py`` holds it
    to ERFA's atciqz + atioq one by one)."""
    alt, az = j2000_to_observed(ra, dec, when, site, ut1_minus_utc_s=dut1)
    ra_date, dec_date = j2000_to_apparent(ra, dec, when)
    return np.asarray(alt), np.asarray(az), np.asarray(ra_date), np.asarray(dec_date)


def _apart_arcsec(alt1: float, az1: float, alt2: float, az2: float) -> float:
    """Great-circle distance between two (alt, az) or (Dec, RA-as-degrees) directions."""
    a1, a2, daz = math.radians(alt1), math.radians(alt2), math.radians(az1 - az2)
    x = math.cos(a2) * math.sin(daz)
    y = math.cos(a1) * math.sin(a2) - math.sin(a1) * math.cos(a2) * math.cos(daz)
    z = math.sin(a1) * math.sin(a2) + math.cos(a1) * math.cos(a2) * math.cos(daz)
    return math.degrees(math.atan2(math.hypot(x, y), z)) * 3600.0


def _worst_apart(
    ra: FloatArray, dec: FloatArray, when: datetime, site: Site, dut1: float = 0.0
) -> tuple[float, float]:
    """Each position alone (the scalar path) against all at once (the vector path): the worst
    distance apart, arcsec, of alt/az and of RA/Dec of date."""
    ref_alt, ref_az, ref_ra, ref_dec = _array_path(ra, dec, when, site, dut1)
    worst = [0.0, 0.0]
    for i, (one_ra, one_dec) in enumerate(zip(ra.tolist(), dec.tolist(), strict=True)):
        alt, az = j2000_to_observed(one_ra, one_dec, when, site, ut1_minus_utc_s=dut1)
        ra_date, dec_date = j2000_to_apparent(one_ra, one_dec, when)
        assert type(alt) is float
        assert type(ra_date) is float
        assert 0.0 <= az < 360.0
        assert 0.0 <= ra_date < 24.0
        assert abs(alt - ref_alt[i]) < MILLIARCSEC_DEG  # the altitude alone too: the guard's
        worst[0] = max(worst[0], _apart_arcsec(alt, az, ref_alt[i], ref_az[i]))
        apart = _apart_arcsec(dec_date, ra_date * 15.0, ref_dec[i], ref_ra[i] * 15.0)
        worst[1] = max(worst[1], apart)
    return worst[0], worst[1]


def _sky(rng: np.random.Generator, count: int) -> tuple[FloatArray, FloatArray]:
    return rng.uniform(0.0, 24.0, count), np.degrees(np.arcsin(rng.uniform(-1.0, 1.0, count)))


def test_random_positions_and_instants_across_fifty_years_equal_the_vector_path() -> None:
    rng = np.random.default_rng(2026)
    worst = 0.0
    for index in range(250):
        when = datetime(1995, 1, 1, tzinfo=UTC) + timedelta(
            seconds=float(rng.uniform(0.0, 50 * 365.25 * 86400))
        )
        dut1 = float(rng.uniform(-0.9, 0.9)) if index % 3 else 0.0
        # The first instant makes the contexts, the second (a poll later) reuses them.
        for later_s in (0.0, float(rng.uniform(0.0, OBSERVER_REUSE_S))):
            moment = when + timedelta(seconds=later_s)
            worst = max(worst, *_worst_apart(*_sky(rng, 6), moment, SITES[index % 5], dut1))
    assert worst < 1e-3, worst


@pytest.mark.parametrize(
    "start",
    [
        datetime(2016, 12, 31, 23, 59, 50, 250_000, tzinfo=UTC),  # a leap second at midnight
        datetime(2026, 6, 30, 23, 59, 55, tzinfo=UTC),  # midnight
        datetime(2026, 3, 20, 12, 0, 0, tzinfo=timezone(timedelta(hours=-7))),  # not UTC
    ],
    ids=["leap-second", "midnight", "utc-7"],
)
def test_a_poll_s_instants_follow_one_another_through_midnight(start: datetime) -> None:
    """Instants 47 ms apart for 25 s, as a 9600-baud poll reads them: the contexts are reused
    within their windows, the Earth rotation advanced in closed form, made anew after them."""
    site = SITES[0]
    rng = np.random.default_rng(7)
    ra, dec = _sky(rng, 2)
    made = []  # the contexts themselves: alive, so no two share an id()
    for step in range(0, 530, 3):
        moment = start + timedelta(milliseconds=47 * step)
        assert max(_worst_apart(ra, dec, moment, site, 0.3)) < 1e-3, moment
        made.append((one_position._last_observer, one_position._last_geocentric))
    contexts = len({id(observer) for observer, _ in made}), len({id(geo) for _, geo in made})
    # One context of each per 10 s, and one more at midnight.
    assert 3 <= contexts[0] <= 5, contexts
    assert 3 <= contexts[1] <= 5, contexts


def test_a_new_site_or_dut1_gets_its_own_context_at_once() -> None:
    """A context is reused only for its site and DUT1: a sync at another site, or a corrected
    DUT1, must not be served from the previous one (15 arcsec for 1 s of DUT1)."""
    when = datetime(2026, 11, 25, 2, 0, tzinfo=UTC)
    ra, dec = _sky(np.random.default_rng(3), 4)
    for site, dut1 in [(SITES[0], 0.0), (SITES[0], 0.9), (SITES[1], 0.9), (SITES[0], 0.0)]:
        assert max(_worst_apart(ra, dec, when, site, dut1)) < 1e-3, (site, dut1)
    moved = j2000_to_observed(7.5, 12.0, when, SITES[0], ut1_minus_utc_s=0.9)
    still = j2000_to_observed(7.5, 12.0, when, SITES[0])
    assert _apart_arcsec(*moved, *still) > 5.0


def test_the_documented_reuse_window_is_the_code_s() -> None:
    astronomy = (Path(__file__).resolve().parents[2] / "docs" / "astronomy.md").read_text()
    assert f"floats for **{OBSERVER_REUSE_S:g} s**" in astronomy
    assert "within **1 mas**" in astronomy


def test_the_scalar_path_refuses_what_the_array_path_refuses() -> None:
    naive = datetime(2026, 11, 25, 2, 0)
    with pytest.raises(ValueError, match="no time zone"):
        j2000_to_observed(7.5, 12.0, naive, SITES[0])
    with pytest.raises(ValueError, match="no time zone"):
        j2000_to_apparent(7.5, 12.0, naive)
    with pytest.raises(ValueError, match="UT1-UTC"):
        j2000_to_observed(7.5, 12.0, datetime.now(UTC), SITES[0], ut1_minus_utc_s=1.5)
    when = datetime(2026, 11, 25, 2, 0, tzinfo=UTC)
    for ra, dec in [(math.inf, 12.0), (7.5, -math.inf), (math.nan, 12.0)]:
        assert all(math.isnan(v) for v in j2000_to_observed(ra, dec, when, SITES[0]))
        assert all(math.isnan(v) for v in j2000_to_apparent(ra, dec, when))


def test_a_reading_in_one_pass_is_its_two_conversions() -> None:
    """``reading_of_j2000`` (a poll's alt/az and RA/Dec of date in one pass) gives exactly what
    the two conversions give, as the reading, the instant (a jump too), the site and the time
    zone of the datetime change; a UTC datetime's fast path is any zero offset's."""
    rng = np.random.default_rng(11)
    start = datetime(2026, 11, 25, 3, 0, tzinfo=UTC)
    steps = [0.0, 0.047, 0.094, 3.0, 11.0, 3600.0, 3600.047, -86400.0]
    for site in SITES[:3]:
        ra, dec = _sky(rng, 2)
        for index, step in enumerate(steps):
            moment = start + timedelta(seconds=step)
            one_ra, one_dec = float(ra[index % 2]), float(dec[index % 2])
            reading = one_position.reading_of_j2000(one_ra, one_dec, moment, site)
            observed = j2000_to_observed(one_ra, one_dec, moment, site)
            apparent = j2000_to_apparent(one_ra, one_dec, moment)
            assert reading == (*observed, *apparent), (site, step)
            zero_offset = moment.astimezone(timezone(timedelta(0)))  # not the UTC singleton
            assert one_position.reading_of_j2000(one_ra, one_dec, zero_offset, site) == reading
            elsewhere = moment.astimezone(timezone(timedelta(hours=5, minutes=30)))
            assert one_position.reading_of_j2000(one_ra, one_dec, elsewhere, site) == reading


def test_a_reading_polled_again_and_again_is_its_two_conversions_each_time() -> None:
    """The poll's common case (the same reading, instants 21 ms apart: ``reading_of_j2000``'s
    inline path) gives exactly what the two conversions give at every instant, through the
    contexts' renewal every 10 s, UTC midnight, a whole day's jump and a change of site."""
    for start in (
        datetime(2026, 11, 25, 3, 0, tzinfo=UTC),
        datetime(2026, 11, 25, 23, 59, 55, tzinfo=UTC),  # across midnight
    ):
        for site in SITES[:2]:
            # 12.6 s, then the same time of day on the next day and on the one before
            for seconds in [*(0.021 * step for step in range(600)), 86400.0, -86400.0]:
                moment = start + timedelta(seconds=seconds)
                reading = one_position.reading_of_j2000(5.5, 20.0, moment, site)
                observed = j2000_to_observed(5.5, 20.0, moment, site)
                apparent = j2000_to_apparent(5.5, 20.0, moment)
                assert reading == (*observed, *apparent), (start, site, seconds)
