"""Sexagesimal formatting and parsing, angle wrapping."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.astro.angles import (
    SexagesimalStyle,
    format_degrees,
    format_hours,
    parse_degrees,
    parse_hours,
    wrap_degrees,
    wrap_hour_angle,
    wrap_hours,
    wrap_signed_degrees,
)

STYLES: list[SexagesimalStyle] = ["units", "colons", "spaces"]


@pytest.mark.parametrize(
    ("hours", "kwargs", "text"),
    [
        (4.953416666666667, {}, "4h 57m 12.3s"),
        (4.953416666666667, {"style": "colons"}, "04:57:12.3"),
        (12.582222222222223, {"decimals": 0, "style": "spaces"}, "12 34 56"),
        (23.999999999, {}, "0h 00m 00.0s"),
        (-1.5, {"signed": True}, "-1h 30m 00.0s"),
        (-1.5, {}, "22h 30m 00.0s"),
        (1.0 - 0.04 / 3600, {"decimals": 1}, "1h 00m 00.0s"),
    ],
)
def test_format_hours(hours: float, kwargs: dict[str, object], text: str) -> None:
    assert format_hours(hours, **kwargs) == text  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("degrees", "kwargs", "text"),
    [
        (26.444166666666668, {}, "+26°26'39\""),
        (-5.5, {"style": "spaces"}, "-05 30 00"),
        (-0.5, {"style": "colons"}, "-00:30:00"),
        (-0.0000001, {}, "+00°00'00\""),
        (359.99999, {"width": 3, "decimals": 1}, "+360°00'00.0\""),
        (89.99999, {"decimals": 2}, "+89°59'59.96\""),
    ],
)
def test_format_degrees(degrees: float, kwargs: dict[str, object], text: str) -> None:
    assert format_degrees(degrees, **kwargs) == text  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("text", "hours"),
    [
        ("12:34:56", 12 + 34 / 60 + 56 / 3600),
        ("12 34 56.5", 12 + 34 / 60 + 56.5 / 3600),
        ("4h 57m 12.3s", 4 + 57 / 60 + 12.3 / 3600),
        ("4h57m12.3s", 4 + 57 / 60 + 12.3 / 3600),
        ("12:34.5", 12 + 34.5 / 60),
        ("12.5", 12.5),
        ("-0:30:00", -0.5),
        ("  7h  ", 7.0),
    ],
)
def test_parse_hours(text: str, hours: float) -> None:
    assert parse_hours(text) == pytest.approx(hours, abs=1e-12)


@pytest.mark.parametrize(
    ("text", "degrees"),
    [
        ("+26°26'39\"", 26 + 26 / 60 + 39 / 3600),
        ("-05 30 00", -5.5),
        ("-00 30 00", -0.5),
        ("−12:00:36", -(12 + 36 / 3600)),
        ("26d26m39s", 26 + 26 / 60 + 39 / 3600),
        ("45°30′15″", 45 + 30 / 60 + 15 / 3600),
        ("+89:59", 89 + 59 / 60),
        ("-33.25", -33.25),
    ],
)
def test_parse_degrees(text: str, degrees: float) -> None:
    assert parse_degrees(text) == pytest.approx(degrees, abs=1e-12)


@pytest.mark.parametrize(
    "text", ["", "abc", "12:60:00", "12:30:60", "12.5:30", "1:2:3:4", "--5", "1e5", "9" * 400]
)
def test_parse_rejects_garbage_with_value_error(text: str) -> None:
    with pytest.raises(ValueError, match=r"hours|cannot read"):
        parse_hours(text)


@given(st.text(max_size=30))
@settings(max_examples=300, deadline=None)
def test_parse_never_raises_anything_but_value_error(text: str) -> None:
    for parse in (parse_hours, parse_degrees):
        try:
            value = parse(text)
        except ValueError:
            continue
        assert np.isfinite(value)


@given(
    st.floats(min_value=0, max_value=24, exclude_max=True),
    st.integers(min_value=0, max_value=4),
    st.sampled_from(STYLES),
)
@settings(max_examples=300, deadline=None)
def test_hours_format_then_parse_round_trip(
    hours: float, decimals: int, style: SexagesimalStyle
) -> None:
    back = parse_hours(format_hours(hours, decimals=decimals, style=style))
    error_s = abs(wrap_hour_angle(back - hours)) * 3600
    assert error_s <= 0.5 * 10**-decimals + 1e-9


@given(
    st.floats(min_value=-90, max_value=90),
    st.integers(min_value=0, max_value=4),
    st.sampled_from(STYLES),
)
@settings(max_examples=300, deadline=None)
def test_degrees_format_then_parse_round_trip(
    degrees: float, decimals: int, style: SexagesimalStyle
) -> None:
    back = parse_degrees(format_degrees(degrees, decimals=decimals, style=style))
    assert abs(back - degrees) * 3600 <= 0.5 * 10**-decimals + 1e-9


@given(
    st.integers(min_value=0, max_value=23),
    st.integers(min_value=0, max_value=59),
    st.integers(min_value=0, max_value=59),
    st.sampled_from(STYLES),
)
@settings(max_examples=200, deadline=None)
def test_canonical_text_parse_then_format_round_trip(
    whole: int, minutes: int, seconds: int, style: SexagesimalStyle
) -> None:
    hours_text = format_hours(whole + minutes / 60 + seconds / 3600, decimals=0, style=style)
    assert format_hours(parse_hours(hours_text), decimals=0, style=style) == hours_text
    for sign in (1, -1):
        degrees_text = format_degrees(
            sign * (whole + minutes / 60 + seconds / 3600), decimals=0, style=style
        )
        assert format_degrees(parse_degrees(degrees_text), style=style) == degrees_text


@given(st.floats(min_value=-1e6, max_value=1e6))
@settings(max_examples=300, deadline=None)
def test_wrapping_ranges_and_equivalence(value: float) -> None:
    for wrap, low, high, period in (
        (wrap_hours, 0, 24, 24),
        (wrap_hour_angle, -12, 12, 24),
        (wrap_degrees, 0, 360, 360),
        (wrap_signed_degrees, -180, 180, 360),
    ):
        wrapped = wrap(value)
        assert low <= wrapped < high
        turns = (value - wrapped) / period
        assert turns == pytest.approx(round(turns), abs=1e-6)


def test_wrapping_edges_and_arrays() -> None:
    assert wrap_hour_angle(12.0) == -12.0
    assert wrap_hour_angle(-12.0) == -12.0
    assert wrap_hours(-1e-17) == 0.0
    assert wrap_hours(24.0) == 0.0
    wrapped = wrap_hours(np.array([25.0, -1.0, 3.0]))
    np.testing.assert_allclose(wrapped, [1.0, 23.0, 3.0])
    assert isinstance(wrap_degrees(-90.0), float)
