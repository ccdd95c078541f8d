"""The horizon and altitude limits every motion command is checked against."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.mount import InvalidValueError, LimitError, Limits


def test_flat_horizon_refuses_below_and_accepts_above() -> None:
    limits = Limits(horizon_deg=10.0)
    limits.check_altaz(10.0, 123.0)
    with pytest.raises(
        LimitError, match=r"altitude 9\.99° .* below the configured horizon of 10\.00°"
    ):
        limits.check_altaz(9.99, 123.0)


def test_maximum_altitude_keeps_out_of_the_zenith() -> None:
    limits = Limits(max_altitude_deg=85.0)
    with pytest.raises(LimitError, match="above the configured limit"):
        limits.check_altaz(86.0, 0.0)


def test_profile_interpolates_and_wraps_through_north() -> None:
    limits = Limits(horizon_deg=0.0, horizon_profile=((90.0, 20.0), (270.0, 10.0)))
    assert limits.horizon_at(90.0) == pytest.approx(20.0)
    assert limits.horizon_at(180.0) == pytest.approx(15.0)
    # 270 -> 450 (=90) wraps through north: halfway is azimuth 0.
    assert limits.horizon_at(0.0) == pytest.approx(15.0)
    assert limits.horizon_at(360.0) == pytest.approx(15.0)
    with pytest.raises(LimitError):
        limits.check_altaz(14.0, 180.0)


def test_profile_never_lowers_the_flat_horizon() -> None:
    limits = Limits(horizon_deg=12.0, horizon_profile=((0.0, 5.0),))
    assert limits.horizon_at(200.0) == 12.0


@pytest.mark.parametrize(
    "kwargs",
    [
        {"horizon_deg": -20.0},
        {"horizon_deg": 30.0, "max_altitude_deg": 20.0},
        {"horizon_profile": ((10.0, 5.0), (5.0, 5.0))},
        {"horizon_profile": ((400.0, 5.0),)},
    ],
)
def test_nonsense_limits_are_refused(kwargs: dict[str, object]) -> None:
    with pytest.raises(InvalidValueError):
        Limits(**kwargs)  # type: ignore[arg-type]


def test_not_a_number_is_refused() -> None:
    with pytest.raises(InvalidValueError):
        Limits().check_altaz(float("nan"), 0.0)


@given(
    points=st.lists(
        st.tuples(st.floats(0, 359.9), st.floats(-10, 89)),
        min_size=1,
        max_size=8,
        unique_by=lambda p: p[0],
    ),
    az=st.floats(-720, 720),
)
def test_profile_horizon_stays_within_its_points(
    points: list[tuple[float, float]], az: float
) -> None:
    profile = tuple(sorted(points))
    limits = Limits(horizon_deg=-10.0, horizon_profile=profile)
    low = min(alt for _, alt in profile)
    high = max(alt for _, alt in profile)
    assert low - 1e-9 <= limits.horizon_at(az) <= high + 1e-9
