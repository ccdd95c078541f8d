"""The Sky Tracker's bias-128 float (``S``/``s`` calibration; Sky Commander ``O``/``R``).

Four bytes, most significant first: bit 31 sign, bits 30-23 exponent biased by 128, bits 22-0
the mantissa below a hidden leading 1: ``value = sign * 2**(exponent - 128) * mantissa`` with
the mantissa in [0.5, 1); zero is four zero bytes. Every such pattern equals the IEEE-754 single
of four times the value, but the format has no infinities, NaNs or denormals: exponent 255 is an
ordinary number and exponent 0 is zero.
"""

from __future__ import annotations

import math

CALFLOAT_SIZE = 4
"""Bytes in one number on the wire."""

_EXPONENT_BIAS = 128
_MANTISSA_BITS = 24  # including the hidden bit
_HIDDEN_BIT = 1 << (_MANTISSA_BITS - 1)
_FRACTION_MASK = _HIDDEN_BIT - 1
_MAX_EXPONENT_FIELD = 0xFF

CALFLOAT_MAX = math.ldexp(1.0 - 2.0**-_MANTISSA_BITS, _MAX_EXPONENT_FIELD - _EXPONENT_BIAS)
"""Largest magnitude the format holds, (1 - 2**-24) * 2**127 (about 1.7e38)."""

CALFLOAT_MIN_NORMAL = math.ldexp(0.5, 1 - _EXPONENT_BIAS)
"""Smallest nonzero magnitude the format holds, 2**-128 (about 2.9e-39)."""


class CalibrationFloatRangeError(ValueError):
    """A number that the bias-128 format cannot hold (NaN, infinity, too large or too small)."""


def encode_calfloat(value: float) -> bytes:
    """Encode ``value`` as 4 bytes, rounding the mantissa to nearest (ties to even).

    Rounding happens first and the range check after it, so a value just below the smallest
    normal magnitude that rounds up to it is accepted. Raises :class:`CalibrationFloatRangeError`
    for NaN, infinities, magnitudes that round above :data:`CALFLOAT_MAX`, and nonzero magnitudes
    that round below :data:`CALFLOAT_MIN_NORMAL` (the format has no denormals; silently sending
    zero would hide the mistake). Negative zero is sent as four zero bytes.
    """
    if math.isnan(value) or math.isinf(value):
        raise CalibrationFloatRangeError(f"{value} cannot be sent as a Sky Tracker float")
    if value == 0.0:
        return bytes(CALFLOAT_SIZE)
    sign = 1 if value < 0 else 0
    mantissa, exponent = math.frexp(abs(value))  # mantissa in [0.5, 1), as the format wants
    # Scaling by a power of two is exact, so round() sees the true value and ties go to even.
    significand = round(math.ldexp(mantissa, _MANTISSA_BITS))
    if significand == 1 << _MANTISSA_BITS:
        significand = _HIDDEN_BIT
        exponent += 1
    exponent_field = exponent + _EXPONENT_BIAS
    if exponent_field > _MAX_EXPONENT_FIELD:
        raise CalibrationFloatRangeError(
            f"{value!r} overflows the Sky Tracker float (largest magnitude {CALFLOAT_MAX!r})"
        )
    if exponent_field < 1:
        raise CalibrationFloatRangeError(
            f"{value!r} underflows the Sky Tracker float "
            f"(smallest nonzero magnitude {CALFLOAT_MIN_NORMAL!r}; send 0 instead)"
        )
    bits = (sign << 31) | (exponent_field << (_MANTISSA_BITS - 1)) | (significand & _FRACTION_MASK)
    return bits.to_bytes(CALFLOAT_SIZE, "big")


def decode_calfloat(data: bytes) -> float:
    """Decode 4 bytes exactly. Any pattern with a zero exponent field decodes as 0.0.

    The hidden-bit rule leaves no other meaning for exponent 0 than zero (the spec's zero is four
    zero bytes); a nonzero sign or mantissa with it is tolerated rather than refused, as the small
    float libraries of the Tracker's era do. Use :func:`is_canonical_calfloat` to detect such bytes.
    """
    if len(data) != CALFLOAT_SIZE:
        raise ValueError(f"a Sky Tracker float is {CALFLOAT_SIZE} bytes, got {len(data)}")
    bits = int.from_bytes(data, "big")
    exponent_field = (bits >> (_MANTISSA_BITS - 1)) & _MAX_EXPONENT_FIELD
    if exponent_field == 0:
        return 0.0
    significand = (bits & _FRACTION_MASK) | _HIDDEN_BIT
    magnitude = math.ldexp(significand, exponent_field - _EXPONENT_BIAS - _MANTISSA_BITS)
    return -magnitude if bits >> 31 else magnitude


def is_canonical_calfloat(data: bytes) -> bool:
    """True when ``data`` is exactly what :func:`encode_calfloat` produces for its value."""
    return len(data) == CALFLOAT_SIZE and (
        data[0] & 0x7F != 0 or data[1] & 0x80 != 0 or not any(data)
    )


def encode_calfloat_pair(first: float, second: float) -> bytes:
    """Two numbers back to back, as ``S``/``s`` and the Sky Commander's ``O``/``R`` carry them."""
    return encode_calfloat(first) + encode_calfloat(second)


def decode_calfloat_pair(data: bytes) -> tuple[float, float]:
    """The two numbers of an 8-byte pair (see :func:`encode_calfloat_pair`)."""
    return decode_calfloat(data[:CALFLOAT_SIZE]), decode_calfloat(
        data[CALFLOAT_SIZE : 2 * CALFLOAT_SIZE]
    )
