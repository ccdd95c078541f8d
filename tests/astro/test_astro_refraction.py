"""Refraction: ERFA's published constants, continuity, monotonicity, exact inverse."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.astro.refraction import (
    BLEND_HIGH_DEG,
    BLEND_LOW_DEG,
    LOWEST_MODELLED_DEG,
    RefractionModel,
    observed_altitude_deg,
    refraction_deg,
    true_altitude_deg,
)
from scopelink.astro.site import Site

STANDARD = Site(45.0, 0.0, pressure_hpa=1010.0, temperature_c=10.0, relative_humidity=0.0)

sites = st.builds(
    Site,
    latitude_deg=st.just(0.0),
    longitude_deg=st.just(0.0),
    pressure_hpa=st.floats(min_value=300, max_value=1200),
    temperature_c=st.floats(min_value=-60, max_value=60),
    relative_humidity=st.floats(min_value=0, max_value=1),
    wavelength_um=st.floats(min_value=0.3, max_value=2.0),
)


def test_erfa_refco_example() -> None:
    # SOFA/ERFA t_refco: 800 hPa, 10 °C, 90 % humidity, 0.4 µm.
    site = Site(
        0.0, 0.0, pressure_hpa=800, temperature_c=10, relative_humidity=0.9, wavelength_um=0.4
    )
    model = RefractionModel.for_site(site)
    assert model.a_rad == pytest.approx(0.2264949956241415009e-3, abs=1e-15)
    assert model.b_rad == pytest.approx(-0.2598658261729343970e-6, abs=1e-18)


def test_erfa_model_above_blend() -> None:
    model = RefractionModel.for_site(STANDARD)
    for altitude in (BLEND_HIGH_DEG, 20.0, 45.0, 89.0):
        tan_z = math.tan(math.radians(90 - altitude))
        expected = math.degrees((model.a_rad + model.b_rad * tan_z**2) * tan_z)
        assert refraction_deg(altitude, STANDARD) == pytest.approx(expected, rel=1e-12)


def test_textbook_values() -> None:
    # Standard air: about 58" at 45° and 34.5' (Bennett) at the horizon.
    assert refraction_deg(45.0, STANDARD) * 3600 == pytest.approx(58.0, abs=1.0)
    assert refraction_deg(0.0, STANDARD) * 60 == pytest.approx(34.5, abs=0.1)
    assert refraction_deg(90.0, STANDARD) == pytest.approx(0.0, abs=1e-15)


def test_pressure_zero_switches_refraction_off() -> None:
    site = STANDARD.without_refraction()
    altitudes = np.linspace(-10, 90, 101)
    np.testing.assert_array_equal(refraction_deg(altitudes, site), 0.0)
    np.testing.assert_array_equal(observed_altitude_deg(altitudes, site), altitudes)
    assert not site.refracts


def test_finite_and_constant_below_lowest_modelled_altitude() -> None:
    deep = refraction_deg(np.array([-90.0, -30.0, -4.4, -2.0]), STANDARD)
    assert np.all(np.isfinite(deep))
    np.testing.assert_allclose(deep, refraction_deg(LOWEST_MODELLED_DEG, STANDARD))


@given(sites)
@settings(max_examples=40, deadline=None)
def test_continuous_and_decreasing_from_minus_one_to_zenith(site: Site) -> None:
    altitudes = np.linspace(LOWEST_MODELLED_DEG, 90.0, 9101)
    amounts = refraction_deg(altitudes, site)
    assert isinstance(amounts, np.ndarray)
    steps = np.diff(amounts)
    assert np.all(steps < 0)
    # Continuity: no step bigger than the steepest slope (0.5 deg/deg, cold dense air at -1°).
    assert np.max(np.abs(steps)) <= 0.5 * (altitudes[1] - altitudes[0])
    # Across each blend edge the left and right limits agree.
    for edge in (BLEND_LOW_DEG, BLEND_HIGH_DEG):
        below, above = np.asarray(refraction_deg(np.array([edge - 1e-9, edge + 1e-9]), site))
        assert abs(below - above) < 1e-9


@given(sites, st.floats(min_value=-30, max_value=90))
@settings(max_examples=300, deadline=None)
def test_refract_and_unrefract_are_exact_inverses(site: Site, true_altitude: float) -> None:
    observed = observed_altitude_deg(true_altitude, site)
    assert observed >= true_altitude
    assert abs(true_altitude_deg(observed, site) - true_altitude) * 3600 < 1e-6


@given(sites, st.floats(min_value=-5, max_value=90))
@settings(max_examples=200, deadline=None)
def test_unrefract_then_refract_round_trip(site: Site, observed: float) -> None:
    back = observed_altitude_deg(true_altitude_deg(observed, site), site)
    assert abs(back - observed) * 3600 < 1e-6


def test_vectorised_matches_scalar() -> None:
    altitudes = np.linspace(-2, 90, 50)
    many = observed_altitude_deg(altitudes, STANDARD)
    assert isinstance(many, np.ndarray)
    singles = [observed_altitude_deg(float(a), STANDARD) for a in altitudes]
    assert all(isinstance(value, float) for value in singles)
    np.testing.assert_allclose(many, singles, rtol=0, atol=1e-12)


@given(sites, st.lists(st.floats(min_value=-30, max_value=90), min_size=1, max_size=20))
@settings(max_examples=150, deadline=None)
def test_the_array_and_single_value_paths_agree(site: Site, altitudes: list[float]) -> None:
    """One altitude goes through ``math`` (a poll's cost), many through numpy and Newton steps:
    the same numbers either way, in both directions."""
    array = np.array(altitudes)
    refracted = np.asarray(observed_altitude_deg(array, site))
    amounts = np.asarray(refraction_deg(array, site))
    for index, altitude in enumerate(altitudes):
        assert abs(observed_altitude_deg(altitude, site) - refracted[index]) < 1e-11
        assert abs(refraction_deg(altitude, site) - amounts[index]) < 1e-13


def test_an_observer_context_reused_within_seconds_matches_a_fresh_one() -> None:
    """Successive single conversions reuse ERFA's observer context, updating only the Earth
    rotation: within 10 s it agrees with a fresh computation to well under a milliarcsecond."""
    from datetime import UTC, datetime, timedelta

    from scopelink.astro import horizontal, j2000_to_observed

    start = datetime(2026, 11, 22, 22, 0, tzinfo=UTC)
    for seconds in (0.0, 0.02, 1.0, 9.9):
        when = start + timedelta(seconds=seconds)
        horizontal._last_observer = None
        j2000_to_observed(5.5, 30.0, start, STANDARD)  # the context is computed here
        reused = j2000_to_observed(5.5, 30.0, when, STANDARD)
        horizontal._last_observer = None
        fresh = j2000_to_observed(5.5, 30.0, when, STANDARD)
        assert abs(reused[0] - fresh[0]) * 3600 < 1e-3
        assert abs(reused[1] - fresh[1]) * 3600 < 1e-3
