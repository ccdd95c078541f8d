"""Property-based tests of the Alpaca request parsing: ids, names, numbers, dates."""

from __future__ import annotations

import math
from collections.abc import Callable
from datetime import UTC, datetime

import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.servers.alpaca import AlpacaError, BadRequest, ErrorNumber
from scopelink.servers.alpaca.params import UINT32_MAX, Params, parse_transaction_id
from scopelink.servers.alpaca.telescope import format_utc, parse_utc


def _outcome(call: Callable[[], object]) -> object:
    """What ``call`` returns, or the Alpaca error it raises (any other exception escapes)."""
    try:
        return call()
    except (BadRequest, AlpacaError) as error:
        return error


@given(st.integers(min_value=0, max_value=UINT32_MAX))
def test_every_uint32_transaction_id_is_accepted(value: int) -> None:
    assert parse_transaction_id("ClientTransactionID", str(value)) == value


@given(st.text(max_size=30))
def test_a_transaction_id_is_canonical_ascii_digits_within_uint32_or_http_400(text: str) -> None:
    valid = text.isascii() and text.isdigit() and int(text) <= UINT32_MAX
    if valid:
        assert parse_transaction_id("ClientID", text) == int(text)
    else:
        with pytest.raises(BadRequest, match="ClientID"):
            parse_transaction_id("ClientID", text)


@pytest.mark.parametrize("text", ["", " ", "-1", "+5", "1.0", "NASDAQ", "4294967296", "²", " 7"])
def test_conformu_style_bad_ids_are_rejected(text: str) -> None:
    with pytest.raises(BadRequest):
        parse_transaction_id("ClientTransactionID", text)


def test_an_absent_transaction_id_is_zero() -> None:
    assert parse_transaction_id("ClientTransactionID", None) == 0


@given(st.sampled_from(["RightAscension", "ClientTransactionID", "Axis"]), st.data())
def test_get_names_match_in_any_casing(name: str, data: st.DataObject) -> None:
    spelt = "".join(data.draw(st.sampled_from([char.lower(), char.upper()])) for char in name)
    params = Params.from_pairs([(spelt, "12")], exact=False)
    assert params.optional(name) == "12"


@given(st.sampled_from(["RightAscension", "Tracking", "Rate"]), st.data())
def test_put_names_match_only_exactly(name: str, data: st.DataObject) -> None:
    spelt = "".join(data.draw(st.sampled_from([char.lower(), char.upper()])) for char in name)
    params = Params.from_pairs([(spelt, "1")], exact=True)
    if spelt == name:
        assert params.text(name) == "1"
    else:
        assert params.optional(name) is None
        with pytest.raises(BadRequest, match="case-sensitive"):
            params.text(name)


@given(st.floats(min_value=-1e6, max_value=1e6))
def test_numbers_round_trip_through_their_text(value: float) -> None:
    params = Params.from_pairs([("Rate", repr(value))], exact=True)
    assert params.number("Rate") == value


@given(st.text(max_size=40))
def test_any_number_text_parses_or_fails_clearly(text: str) -> None:
    params = Params.from_pairs([("Rate", text)], exact=True)
    value = _outcome(lambda: params.number("Rate", -10.0, 10.0))
    if isinstance(value, BadRequest):
        assert "Rate" in str(value)
    elif isinstance(value, AlpacaError):
        assert value.number is ErrorNumber.INVALID_VALUE
    else:
        assert isinstance(value, float)
        assert math.isfinite(value)
        assert -10.0 <= value <= 10.0


@pytest.mark.parametrize("text", ["nan", "NaN", "inf", "-Infinity", "1e999", "25", "-0.5"])
def test_non_finite_or_out_of_range_numbers_are_invalid_values(text: str) -> None:
    params = Params.from_pairs([("RightAscension", text)], exact=True)
    with pytest.raises(AlpacaError) as caught:
        params.number("RightAscension", 0.0, 24.0)
    assert caught.value.number is ErrorNumber.INVALID_VALUE
    if text.lower().lstrip("+-") in ("nan", "inf", "infinity"):
        assert "must be a finite number" in str(caught.value), caught.value


def test_a_non_finite_number_without_bounds_says_so() -> None:
    """A NaN rate read "must lie within [-inf, inf]": true, and no help."""
    params = Params.from_pairs([("DeclinationRate", "NaN")], exact=True)
    with pytest.raises(AlpacaError, match=r"^DeclinationRate NaN must be a finite number$"):
        params.number("DeclinationRate")


@pytest.mark.parametrize("text", ["fast", "", "1_0", "0x10", "١٢", "1,5"])
def test_malformed_numbers_are_bad_requests(text: str) -> None:
    params = Params.from_pairs([("Rate", text)], exact=True)
    with pytest.raises(BadRequest):
        params.number("Rate")


@given(st.text(max_size=30))
def test_integers_parse_or_fail_clearly(text: str) -> None:
    params = Params.from_pairs([("Axis", text)], exact=True)
    value = _outcome(lambda: params.integer("Axis", 0, 2))
    if isinstance(value, AlpacaError):
        assert value.number is ErrorNumber.INVALID_VALUE
    elif not isinstance(value, BadRequest):
        assert value in (0, 1, 2)


def test_a_huge_integer_is_an_invalid_value_not_a_crash() -> None:
    params = Params.from_pairs([("Duration", "9" * 5000)], exact=True)
    with pytest.raises(AlpacaError):
        params.integer("Duration", 0, 60_000)


@given(st.sampled_from(["True", "true", "TRUE", "False", "false"]))
def test_booleans_ignore_case(text: str) -> None:
    params = Params.from_pairs([("Tracking", text)], exact=True)
    assert params.boolean("Tracking") is (text.lower() == "true")


@pytest.mark.parametrize("text", ["", "1", "yes", "123456", "asdqwe"])
def test_other_booleans_are_bad_requests(text: str) -> None:
    with pytest.raises(BadRequest):
        Params.from_pairs([("Connected", text)], exact=True).boolean("Connected")


@given(
    st.datetimes(
        min_value=datetime(1900, 1, 1), max_value=datetime(2200, 1, 1), timezones=st.just(UTC)
    )
)
def test_utc_dates_round_trip(when: datetime) -> None:
    text = format_utc(when)
    assert text.endswith("Z")
    assert parse_utc(text) == when


def test_dotnet_seven_digit_fractions_and_offsets_are_accepted() -> None:
    assert parse_utc("2027-03-04T05:06:07.1234567Z") == datetime(
        2027, 3, 4, 5, 6, 7, 123456, tzinfo=UTC
    )
    assert parse_utc("2027-03-04T07:06:07+02:00") == datetime(2027, 3, 4, 5, 6, 7, tzinfo=UTC)
    assert parse_utc("2027-03-04T05:06:07") == datetime(2027, 3, 4, 5, 6, 7, tzinfo=UTC)


@given(st.text(max_size=40))
def test_any_date_text_parses_or_is_an_invalid_value(text: str) -> None:
    when = _outcome(lambda: parse_utc(text))
    if isinstance(when, AlpacaError):
        assert when.number is ErrorNumber.INVALID_VALUE
    else:
        assert isinstance(when, datetime)
        assert when.tzinfo is UTC
