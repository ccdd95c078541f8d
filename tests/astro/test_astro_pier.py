"""Hour angle wrapping, German-equatorial pier side, angular separation."""

from __future__ import annotations

import erfa
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.astro.pier import (
    PierSide,
    angular_separation_deg,
    destination_side_of_pier,
    hour_angle_hours,
)

hours = st.floats(min_value=-48, max_value=48)


@given(hours, hours)
@settings(max_examples=300, deadline=None)
def test_hour_angle_is_wrapped_and_consistent(lst: float, ra: float) -> None:
    ha = hour_angle_hours(lst, ra)
    assert -12 <= ha < 12
    turns = (lst - ra - ha) / 24
    assert turns == pytest.approx(round(turns), abs=1e-9)


def test_hour_angle_examples_and_arrays() -> None:
    assert hour_angle_hours(1.0, 23.0) == pytest.approx(2.0)
    assert hour_angle_hours(23.0, 1.0) == pytest.approx(-2.0)
    assert hour_angle_hours(6.0, 18.0) == -12.0
    many = hour_angle_hours(np.array([0.0, 6.0, 12.0]), 3.0)
    np.testing.assert_allclose(many, [-3.0, 3.0, 9.0])


@pytest.mark.parametrize(
    ("ha", "side"),
    [
        (3.0, PierSide.EAST),  # target west of the meridian: tube east of the pier
        (11.9, PierSide.EAST),
        (-3.0, PierSide.WEST),  # target east of the meridian: tube west of the pier
        (0.0, PierSide.WEST),
        (-12.0, PierSide.WEST),
        (27.0, PierSide.EAST),  # wrapped to 3 h
        (float("nan"), PierSide.UNKNOWN),
    ],
)
def test_destination_side_of_pier(ha: float, side: PierSide) -> None:
    assert destination_side_of_pier(ha) is side


def test_pier_side_values_are_ascoms() -> None:
    assert (PierSide.EAST, PierSide.WEST, PierSide.UNKNOWN) == (0, 1, -1)


lon = st.floats(min_value=-720, max_value=720)
lat = st.floats(min_value=-90, max_value=90)


@given(lon, lat, lon, lat)
@settings(max_examples=300, deadline=None)
def test_separation_matches_erfa(lon1: float, lat1: float, lon2: float, lat2: float) -> None:
    expected = np.degrees(
        erfa.seps(np.radians(lon1), np.radians(lat1), np.radians(lon2), np.radians(lat2))
    )
    assert angular_separation_deg(lon1, lat1, lon2, lat2) == pytest.approx(expected, abs=1e-9)


def test_separation_is_accurate_when_tiny_and_near_antipodal() -> None:
    tiny = 1e-9
    assert angular_separation_deg(10.0, 20.0, 10.0, 20.0 + tiny) == pytest.approx(tiny, rel=1e-6)
    assert angular_separation_deg(0.0, 0.0, 180.0, tiny) == pytest.approx(180.0 - tiny, abs=1e-12)
    many = angular_separation_deg(np.zeros(3), np.zeros(3), np.array([0.0, 90.0, 180.0]), 0.0)
    np.testing.assert_allclose(many, [0.0, 90.0, 180.0], atol=1e-12)
