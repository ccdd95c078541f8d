"""The vectorised J2000/apparent -> observed path equals the per-position ERFA reference path.

Many positions at one instant go through ERFA's ldsun/ab, one matrix for the Earth rotation and
the refraction's Newton iteration with a closed-form slope (``horizontal._observed_from_vectors``);
one position goes through ``erfa.atciqz`` + ``erfa.atioq`` and the scalar refraction. The two must
agree to far below a milliarcsecond, everywhere on the sky and through the horizon blend.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from datetime import UTC, datetime, timedelta

import numpy as np
import numpy.typing as npt
import pytest

from scopelink.astro._arrays import FloatArray
from scopelink.astro.horizontal import apparent_to_observed, j2000_to_observed, observed_to_j2000
from scopelink.astro.refraction import RefractionModel
from scopelink.astro.site import Site

MICROARCSEC_DEG = 1e-6 / 3600.0
SITES = [
    Site(51.4779, -0.0015, 46.0),
    Site(-31.2734, 149.0664, 1165.0, temperature_c=-5.0, relative_humidity=0.9),
    Site(78.2, 15.6, 10.0, pressure_hpa=0.0),
    Site(-89.99, 139.27, 2835.0, temperature_c=-55.0),
]
WHEN = datetime(2026, 11, 22, 22, 0, 13, 250_000, tzinfo=UTC)


def _sky(count: int, seed: int) -> tuple[FloatArray, FloatArray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(0.0, 24.0, count), np.degrees(np.arcsin(rng.uniform(-1.0, 1.0, count)))


def _separation_deg(
    alt1: npt.ArrayLike, az1: npt.ArrayLike, alt2: npt.ArrayLike, az2: npt.ArrayLike
) -> FloatArray:
    """Great-circle distance, in degrees, between two arrays of (alt, az) directions."""
    a1, a2 = np.radians(np.asarray(alt1)), np.radians(np.asarray(alt2))
    daz = np.radians(np.asarray(az1) - np.asarray(az2))
    x = np.cos(a2) * np.sin(daz)
    y = np.cos(a1) * np.sin(a2) - np.sin(a1) * np.cos(a2) * np.cos(daz)
    z = np.sin(a1) * np.sin(a2) + np.cos(a1) * np.cos(a2) * np.cos(daz)
    separation: FloatArray = np.degrees(np.arctan2(np.hypot(x, y), z))
    return separation


def _floats(pair: tuple[object, object]) -> tuple[float, float]:
    return float(pair[0]), float(pair[1])  # type: ignore[arg-type]


Convert = Callable[[float, float, datetime, Site], tuple[float, float]]


def _one_by_one(
    convert: Convert, ra: npt.ArrayLike, dec: npt.ArrayLike, when: datetime, site: Site
) -> tuple[FloatArray, FloatArray]:
    # 0-d arrays: ERFA's atciqz + atioq one position at a time (floats take the float path,
    # astro.one_position, held to this one in test_astro_one_position.py).
    pairs = [
        convert(np.asarray(r), np.asarray(d), when, site)  # type: ignore[arg-type]
        for r, d in zip(np.asarray(ra), np.asarray(dec), strict=True)
    ]
    return np.array([float(p[0]) for p in pairs]), np.array([float(p[1]) for p in pairs])


@pytest.mark.parametrize("site", SITES, ids=lambda s: f"lat{s.latitude_deg:+.0f}")
@pytest.mark.parametrize("convert", [j2000_to_observed, apparent_to_observed])
def test_vector_path_equals_the_per_position_reference(site: Site, convert: Convert) -> None:
    ra, dec = _sky(600, 14)
    alt, az = convert(ra, dec, WHEN, site)  # type: ignore[arg-type]
    ref_alt, ref_az = _one_by_one(convert, ra, dec, WHEN, site)
    assert np.all(np.abs(alt - ref_alt) < MICROARCSEC_DEG)
    assert np.all(_separation_deg(alt, az, ref_alt, ref_az) < MICROARCSEC_DEG)


def test_vector_path_through_the_horizon_blend() -> None:
    """Dense positions from -2 to +8 degrees of altitude: Bennett, the 5-6 degree blend, ERFA."""
    site = SITES[0]
    grid_alt, grid_az = np.meshgrid(np.linspace(-2.0, 8.0, 401), [15.0, 160.0, 290.0])
    ra, dec = observed_to_j2000(grid_alt.ravel(), grid_az.ravel(), WHEN, site)
    alt, az = j2000_to_observed(ra, dec, WHEN, site)
    ref_alt, ref_az = _one_by_one(j2000_to_observed, ra, dec, WHEN, site)
    assert np.all(np.abs(alt - grid_alt.ravel()) < 1e-6)
    assert np.all(np.abs(alt - ref_alt) < MICROARCSEC_DEG)
    assert np.all(_separation_deg(alt, az, ref_alt, ref_az) < MICROARCSEC_DEG)


def test_shapes_and_broadcasting_are_kept() -> None:
    ra, dec = _sky(60, 3)
    alt, az = np.asarray(j2000_to_observed(ra.reshape(6, 10), dec.reshape(6, 10), WHEN, SITES[1]))
    flat_alt, flat_az = j2000_to_observed(ra, dec, WHEN, SITES[1])
    assert alt.shape == az.shape == (6, 10)
    np.testing.assert_allclose(alt.ravel(), flat_alt, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(az.ravel(), flat_az, rtol=0.0, atol=1e-12)
    one_dec_alt, _ = j2000_to_observed(ra, 12.5, WHEN, SITES[1])
    ref_alt, _ = _one_by_one(j2000_to_observed, ra, np.full_like(ra, 12.5), WHEN, SITES[1])
    assert np.all(np.abs(one_dec_alt - ref_alt) < MICROARCSEC_DEG)


def test_many_instants_still_agree_with_one_instant_each() -> None:
    """Positions at their own instants (the reference path) equal each instant done alone."""
    ra, dec = _sky(5, 8)
    instants = [WHEN + timedelta(minutes=17 * i) for i in range(5)]
    jd1 = np.array([2440587.5 + (t.timestamp() // 86400) for t in instants])
    jd2 = np.array([(t.timestamp() % 86400) / 86400.0 for t in instants])
    alt = np.asarray(j2000_to_observed(ra, dec, (jd1, jd2), SITES[0])[0])
    for i, t in enumerate(instants):
        single = np.asarray(j2000_to_observed(ra[i : i + 1], dec[i : i + 1], t, SITES[0])[0])
        assert math.isclose(float(alt[i]), float(single[0]), abs_tol=MICROARCSEC_DEG)


@pytest.mark.parametrize("site", SITES, ids=lambda s: f"lat{s.latitude_deg:+.0f}")
def test_newton_refraction_equals_the_scalar_fixed_point(site: Site) -> None:
    model = RefractionModel.for_site(site)
    true = np.concatenate([np.linspace(-5.0, 12.0, 3401), np.linspace(12.0, 90.0, 400)])
    fast = model.refract(true)
    reference = np.array([model.refract(float(t)) for t in true])
    assert np.all(np.abs(fast - reference) < MICROARCSEC_DEG)
    assert np.all(np.abs(model.unrefract(fast) - true) < 1e-11)


def test_a_geocentric_context_reused_within_a_second_matches_a_fresh_one() -> None:
    """j2000_to_apparent for one instant reuses erfa.apci13 within 1 s: 1e-5 arcsec at most."""
    from scopelink.astro import frames

    rng = np.random.default_rng(5)
    for seconds in (0.0, 0.013, 0.5, 0.999):
        when = WHEN + timedelta(seconds=seconds)
        # A 0-d RA: the array path and its context cache (floats have one_position's own).
        ra, dec = np.asarray(rng.uniform(0, 24)), float(rng.uniform(-89, 89))
        frames._last_geocentric = None
        frames.j2000_to_apparent(ra, dec, WHEN)  # the context is computed here
        reused = _floats(frames.j2000_to_apparent(ra, dec, when))
        frames._last_geocentric = None
        fresh = _floats(frames.j2000_to_apparent(ra, dec, when))
        assert abs(reused[1] - fresh[1]) * 3600 < 1e-5
        assert abs(reused[0] - fresh[0]) * 15 * 3600 * math.cos(math.radians(dec)) < 1e-5
        back = frames.apparent_to_j2000(*reused, when)
        assert abs(back[1] - dec) * 3600 < 1e-5


def test_a_datetime_gives_erfa_dtf2d_julian_date_bit_for_bit() -> None:
    """The cached-day conversion of a datetime equals erfa.dtf2d, leap-second days included."""
    import erfa

    from scopelink.astro.timescales import utc_pair

    rng = np.random.default_rng(9)
    days = [datetime(2016, 12, 31, tzinfo=UTC), datetime(2015, 6, 30, tzinfo=UTC), WHEN]
    for start in days:
        for offset in rng.uniform(0.0, 86399.999, 300):
            moment = start.replace(hour=0, minute=0, second=0, microsecond=0) + timedelta(
                seconds=float(offset)
            )
            seconds = moment.second + moment.microsecond * 1e-6
            expected = erfa.dtf2d(
                "UTC", moment.year, moment.month, moment.day, moment.hour, moment.minute, seconds
            )
            jd1, jd2 = utc_pair(moment)
            assert (float(jd1), float(jd2)) == (float(expected[0]), float(expected[1]))


def test_a_reused_observer_context_has_aper13s_earth_rotation_exactly() -> None:
    """The reused context's local ERA (era00 + longitude) equals erfa.aper13's, bit for bit, and
    the cached context itself is never changed (a worker thread may be using it)."""
    import erfa

    from scopelink.astro import horizontal
    from scopelink.astro.timescales import utc_pair

    site = SITES[1]
    vars(horizontal)["_last_observer"] = None
    horizontal._observer(WHEN, site, 0.2)
    cached = horizontal._last_observer
    assert cached is not None
    base = cached.astrom.copy()
    for step in range(0, 2000, 7):
        moment = WHEN + timedelta(milliseconds=4.9 * step)
        astrom, _ = horizontal._observer(moment, site, 0.2)
        ut1 = erfa.utcut1(*utc_pair(moment), 0.2)
        assert astrom["eral"] == erfa.aper13(*ut1, base.copy())["eral"]
        assert cached.astrom["eral"] == base["eral"]


def test_single_value_wrapping_equals_the_array_arithmetic() -> None:
    from scopelink.astro.angles import wrap_degrees, wrap_hour_angle
    from scopelink.astro.frames import radec_public

    rng = np.random.default_rng(11)
    values = np.concatenate([rng.uniform(-1000.0, 1000.0, 500), [-1e-17, 0.0, 360.0, -360.0]])
    for value in values:
        assert wrap_degrees(float(value)) == float(np.asarray(wrap_degrees(np.array([value])))[0])
        assert wrap_hour_angle(float(value)) == float(
            np.asarray(wrap_hour_angle(np.array([value])))[0]
        )
        one = radec_public(float(value) / 100.0, float(value) / 1000.0)
        ra, dec = radec_public(np.array([value / 100.0]), np.array([value / 1000.0]))
        assert one == (float(np.asarray(ra)[0]), float(np.asarray(dec)[0]))


def test_one_hour_angle_to_altaz_equals_erfa_hd2ae_bit_for_bit() -> None:
    from scopelink.astro.horizontal import hadec_to_altaz

    rng = np.random.default_rng(21)
    for ha, dec, lat in rng.uniform([-12.0, -90.0, -90.0], [12.0, 90.0, 90.0], (3000, 3)):
        one = hadec_to_altaz(float(ha), float(dec), float(lat))
        alt, az = hadec_to_altaz(np.array([ha]), np.array([dec]), np.array([lat]))
        assert one == (float(np.asarray(alt)[0]), float(np.asarray(az)[0]))
    assert hadec_to_altaz(0.0, 90.0, 90.0) == hadec_to_altaz(np.zeros(1), [90.0], [90.0])
