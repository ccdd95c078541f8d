"""Geometry round trips in both hemispheres, pier sides, presets and the SynScan rate table."""

from __future__ import annotations

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from scopelink.astro import SIDEREAL_RATE_DEG_S, PierSide, altaz_to_hadec, angular_separation_deg
from scopelink.mount import AlignmentMode, GuideDirection
from scopelink.sim import (
    AZ_GTI,
    EQ6,
    PRESETS,
    SKY_TRACKER,
    SYNSCAN_FIXED_RATES_DEG_S,
    AltAzimuthGeometry,
    ForkEquatorialGeometry,
    GermanEquatorialGeometry,
    geometry_for,
    synscan_fixed_rate_deg_s,
)

latitudes = st.one_of(st.floats(5.0, 85.0), st.floats(-85.0, -5.0))
altitudes = st.floats(-80.0, 89.0)
azimuths = st.floats(0.0, 359.999)


def close(a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Same direction on the sky (alt, az) to a micro-arcsecond."""
    return angular_separation_deg(a[1], a[0], b[1], b[0]) < 1e-9


@settings(max_examples=200, deadline=None)
@given(latitude=latitudes, alt=altitudes, az=azimuths, flipped=st.booleans())
def test_gem_round_trip_on_either_side(
    latitude: float, alt: float, az: float, flipped: bool
) -> None:
    _, dec = altaz_to_hadec(alt, az, latitude)
    assume(abs(dec) < 90.0 - 1e-6)  # at the pole itself both sides are the same pointing
    geometry = GermanEquatorialGeometry(latitude)
    normal = geometry.normal_side
    other = PierSide.WEST if normal is PierSide.EAST else PierSide.EAST
    side = other if flipped else normal
    primary, secondary = geometry.to_axes(alt, az, side)
    assert geometry.pier_side(primary, secondary) is side
    assert close(geometry.to_observed(primary, secondary), (alt, az))


@settings(max_examples=200, deadline=None)
@given(latitude=latitudes, alt=altitudes, az=azimuths)
def test_gem_ascom_side_needs_no_counterweight_up(latitude: float, alt: float, az: float) -> None:
    geometry = GermanEquatorialGeometry(latitude, meridian_tolerance_deg=0.0)
    side = geometry.choose_side(alt, az, PierSide.UNKNOWN)
    primary, secondary = geometry.to_axes(alt, az, side)
    assert abs(primary) <= 90.0 + 1e-9
    assert geometry.axis_margin_deg(primary, secondary) >= -1e-9
    ha, _ = altaz_to_hadec(alt, az, latitude)
    assert side is (PierSide.EAST if ha > 0.0 else PierSide.WEST)


@settings(max_examples=100, deadline=None)
@given(latitude=latitudes, alt=altitudes, az=azimuths)
def test_fork_and_altaz_round_trips(latitude: float, alt: float, az: float) -> None:
    for geometry in (ForkEquatorialGeometry(latitude), AltAzimuthGeometry(latitude)):
        counters = geometry.to_axes(alt, az, PierSide.UNKNOWN)
        assert close(geometry.to_observed(*counters), (alt, az))
        assert geometry.pier_side(*counters) is PierSide.UNKNOWN


@pytest.mark.parametrize("latitude", [40.0, -40.0])
def test_gem_home_points_at_the_visible_pole(latitude: float) -> None:
    geometry = GermanEquatorialGeometry(latitude)
    alt, az = geometry.to_observed(*geometry.home)
    assert alt == pytest.approx(abs(latitude))
    assert az == pytest.approx(0.0 if latitude > 0 else 180.0, abs=1e-9)


@pytest.mark.parametrize("latitude", [40.0, -40.0])
def test_gem_guide_directions_move_the_right_way(latitude: float) -> None:
    geometry = GermanEquatorialGeometry(latitude)
    for side in (PierSide.EAST, PierSide.WEST):
        primary, secondary = geometry.to_axes(50.0, 200.0 if latitude > 0 else 20.0, side)
        ha, dec = geometry.to_hadec(primary, secondary)
        expected = {
            GuideDirection.NORTH: (0.0, 1.0),
            GuideDirection.SOUTH: (0.0, -1.0),
            GuideDirection.WEST: (1.0, 0.0),
            GuideDirection.EAST: (-1.0, 0.0),
        }
        for direction, (ha_sign, dec_sign) in expected.items():
            index, sign = geometry.guide_axis(direction, secondary)
            nudged = [primary, secondary]
            nudged[index] += sign * 0.01
            new_ha, new_dec = geometry.to_hadec(*nudged)
            assert (new_ha - ha) * ha_sign >= 0.0, (side, direction)
            assert (new_dec - dec) * dec_sign >= 0.0, (side, direction)
            assert (new_ha, new_dec) != (ha, dec)


def test_geometry_for_each_alignment_mode() -> None:
    assert isinstance(geometry_for(AlignmentMode.GERMAN_POLAR, 10.0), GermanEquatorialGeometry)
    assert isinstance(geometry_for(AlignmentMode.POLAR, 10.0), ForkEquatorialGeometry)
    assert isinstance(geometry_for(AlignmentMode.ALT_AZ, 10.0), AltAzimuthGeometry)


def test_synscan_fixed_rate_table() -> None:
    assert len(SYNSCAN_FIXED_RATES_DEG_S) == 9
    assert list(SYNSCAN_FIXED_RATES_DEG_S) == sorted(SYNSCAN_FIXED_RATES_DEG_S)
    assert synscan_fixed_rate_deg_s(0) == 0.0
    assert synscan_fixed_rate_deg_s(1) == pytest.approx(2 * SIDEREAL_RATE_DEG_S)
    assert synscan_fixed_rate_deg_s(2) == pytest.approx(8 * SIDEREAL_RATE_DEG_S)
    assert synscan_fixed_rate_deg_s(9) == pytest.approx(3.34, abs=0.01)
    with pytest.raises(ValueError, match=r"0\.\.9"):
        synscan_fixed_rate_deg_s(10)


def test_presets() -> None:
    assert EQ6.max_rate_deg_s == pytest.approx(3.4, abs=0.1)
    assert EQ6.max_rate_deg_s / EQ6.acceleration_deg_s2 == pytest.approx(1.0)
    assert EQ6.synscan_model_code == 0
    assert AZ_GTI.alignment_mode is AlignmentMode.ALT_AZ
    assert SKY_TRACKER.max_rate_deg_s == 4.0
    assert SKY_TRACKER.synscan_model_code is None
    assert PRESETS["heq5"].synscan_model_code == 1
    assert EQ6.guide_rate_deg_s == pytest.approx(0.5 * SIDEREAL_RATE_DEG_S)
