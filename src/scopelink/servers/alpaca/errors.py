"""ASCOM error numbers, and how the Mount API's errors map onto them.

Alpaca reports a failed operation with HTTP 200 and a non-zero ``ErrorNumber`` in the JSON body
(the numbers of ASCOM's COM exceptions less 0x80040000). A request the server cannot even
parse is an HTTP 400 with a plain-text body instead: see :class:`BadRequest`.
"""

from __future__ import annotations

import enum

from scopelink.mount import (
    DeviceError,
    InvalidValueError,
    LimitError,
    MountError,
    NotConnectedError,
    NotSupportedError,
    ParkedError,
)

__all__ = ["AlpacaError", "BadRequest", "ErrorNumber", "from_mount_error"]


class ErrorNumber(enum.IntEnum):
    """The ASCOM error numbers Alpaca uses (``ErrorNumber`` in every reply)."""

    OK = 0
    NOT_IMPLEMENTED = 0x400
    INVALID_VALUE = 0x401
    VALUE_NOT_SET = 0x402
    NOT_CONNECTED = 0x407
    INVALID_WHILE_PARKED = 0x408
    INVALID_WHILE_SLAVED = 0x409
    INVALID_OPERATION = 0x40B
    ACTION_NOT_IMPLEMENTED = 0x40C
    OPERATION_CANCELLED = 0x40E
    DRIVER_ERROR = 0x500
    """First of the driver-specific range 0x500-0xFFF: the device failed; the message says how."""


class AlpacaError(Exception):
    """An ASCOM error answered with HTTP 200 and ``ErrorNumber``/``ErrorMessage`` set."""

    def __init__(self, number: ErrorNumber, message: str) -> None:
        super().__init__(message)
        self.number = number
        self.message = message


class BadRequest(Exception):  # noqa: N818 - named after the HTTP status it becomes
    """A request the server cannot interpret: HTTP 400 with this plain-text message."""


def from_mount_error(error: MountError) -> AlpacaError:
    """The ASCOM error a client sees for a :class:`MountError`.

    ``LimitError`` becomes InvalidValue (0x401): the coordinates are well formed, but they name
    a place this mount may not point at, which is what ASCOM's "invalid coordinates" covers.
    ``ParkedError`` is ASCOM's InvalidWhileParked (0x408).
    """
    message = str(error) or type(error).__name__
    if isinstance(error, NotSupportedError):
        return AlpacaError(ErrorNumber.NOT_IMPLEMENTED, message)
    if isinstance(error, InvalidValueError | LimitError):
        return AlpacaError(ErrorNumber.INVALID_VALUE, message)
    if isinstance(error, ParkedError):
        return AlpacaError(ErrorNumber.INVALID_WHILE_PARKED, message)
    if isinstance(error, NotConnectedError):
        return AlpacaError(ErrorNumber.NOT_CONNECTED, message)
    if isinstance(error, DeviceError):
        return AlpacaError(ErrorNumber.DRIVER_ERROR, f"device error: {message}")
    return AlpacaError(ErrorNumber.DRIVER_ERROR, message)
