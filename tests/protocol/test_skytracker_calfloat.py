"""The bias-128 float and the calibration factors (spec "Floating Point Format", NOTES.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.protocol.skytracker import (
    CALFLOAT_MAX,
    CALFLOAT_MIN_NORMAL,
    CalibrationFloatRangeError,
    azimuth_factor,
    bearing_diameter_in,
    decode_calfloat,
    elevation_factor,
    encode_calfloat,
    ground_board_diameter_in,
    is_canonical_calfloat,
)
from tests.support.skytracker_codec import canonical_calfloat_bytes


@pytest.mark.parametrize(
    ("value", "wire"),
    [
        (0.5, "40 00 00 00"),
        (1.0, "40 80 00 00"),
        (-1.0, "C0 80 00 00"),
        (0.0, "00 00 00 00"),
        (16625.0, "47 81 E2 00"),
        (40037.5, "48 1C 65 80"),
    ],
)
def test_spec_and_notes_vectors(value: float, wire: str) -> None:
    assert encode_calfloat(value) == bytes.fromhex(wire)
    assert decode_calfloat(bytes.fromhex(wire)) == value


def test_exponent_field_is_biased_by_128_with_mantissa_in_half_open_unit() -> None:
    # Spec example: exponent 131 (+3) means 2**3 * mantissa; mantissa 0.75 -> 6.0.
    assert decode_calfloat(bytes([0x41, 0xC0, 0, 0])) == 2**3 * 0.75


def test_negative_zero_is_sent_as_four_zero_bytes() -> None:
    assert encode_calfloat(-0.0) == bytes(4)


def test_zero_exponent_decodes_as_zero_whatever_the_other_bits() -> None:
    for pattern in ("80 00 00 00", "00 00 00 01", "80 7F FF FF"):
        data = bytes.fromhex(pattern)
        assert decode_calfloat(data) == 0.0
        assert not is_canonical_calfloat(data)
    assert is_canonical_calfloat(bytes(4))


def test_largest_and_smallest_magnitudes() -> None:
    assert encode_calfloat(CALFLOAT_MAX) == bytes.fromhex("7F FF FF FF")
    assert encode_calfloat(-CALFLOAT_MIN_NORMAL) == bytes.fromhex("80 80 00 00")
    # Just below the smallest normal, but rounding to it at 24 bits: accepted.
    assert encode_calfloat(CALFLOAT_MIN_NORMAL * (1 - 2**-26)) == bytes.fromhex("00 80 00 00")


@pytest.mark.parametrize(
    "value",
    [
        math.nan,
        math.inf,
        -math.inf,
        math.ldexp(1 - 2**-25, 127),  # halfway above the largest: ties to even overflow
        2.0**128,
        -1e39,
        CALFLOAT_MIN_NORMAL / 2,  # denormal range of the IEEE equivalent: the format has none
        5e-324,
    ],
)
def test_unrepresentable_numbers_raise_a_range_error(value: float) -> None:
    with pytest.raises(CalibrationFloatRangeError):
        encode_calfloat(value)


def test_decode_wants_exactly_four_bytes() -> None:
    with pytest.raises(ValueError, match="4 bytes"):
        decode_calfloat(b"\x40\x00\x00")


@given(canonical_calfloat_bytes)
def test_every_canonical_pattern_survives_decode_then_encode(data: bytes) -> None:
    assert encode_calfloat(decode_calfloat(data)) == data


@given(st.binary(min_size=4, max_size=4))
def test_every_pattern_decodes_like_the_ieee_single_of_four_times_the_value(data: bytes) -> None:
    value = decode_calfloat(data)
    if data[0] & 0x7F == 0 and data[1] & 0x80 == 0:
        assert value == 0.0
    elif data[0] & 0x7F != 0x7F or data[1] & 0x80 == 0:  # IEEE exponent 255 is inf/NaN there
        assert value * 4 == float(np.frombuffer(data, dtype=">f4")[0])


magnitudes = st.floats(min_value=CALFLOAT_MIN_NORMAL, max_value=CALFLOAT_MAX * (1 - 2**-24))


@given(magnitudes, st.booleans())
def test_encoding_rounds_to_within_half_an_ulp_of_a_24_bit_mantissa(
    magnitude: float, negative: bool
) -> None:
    value = -magnitude if negative else magnitude
    back = decode_calfloat(encode_calfloat(value))
    _, exponent = math.frexp(value)
    assert abs(back - value) <= math.ldexp(1.0, exponent - 25)


@given(st.floats(min_value=CALFLOAT_MIN_NORMAL, max_value=8e37), st.booleans())
def test_encoding_matches_numpy_float32_of_four_times_the_value(
    magnitude: float, negative: bool
) -> None:
    value = -magnitude if negative else magnitude
    assert encode_calfloat(value) == np.array([4 * value], dtype=">f4").tobytes()


def test_calibration_factor_examples() -> None:
    assert azimuth_factor(20.0) == 16625.0
    assert elevation_factor(8.0) == 40037.5
    assert ground_board_diameter_in(16625.0) == 20.0
    assert bearing_diameter_in(40037.5) == 8.0


def test_calibration_factor_survives_the_wire_to_float_precision() -> None:
    factor = azimuth_factor(23.5)
    wire_factor = decode_calfloat(encode_calfloat(factor))
    assert ground_board_diameter_in(wire_factor) == pytest.approx(23.5, rel=2**-24)


@pytest.mark.parametrize("bad", [0.0, -3.0, math.nan, math.inf])
def test_calibration_helpers_refuse_nonsense_sizes(bad: float) -> None:
    for helper in (azimuth_factor, elevation_factor, ground_board_diameter_in, bearing_diameter_in):
        with pytest.raises(ValueError, match="positive finite"):
            helper(bad)
