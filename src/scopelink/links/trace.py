"""DEBUG hex trace of every byte a link reads or writes (logger ``scopelink.links.trace``).

One line per transfer: link name, direction (``-->`` written, ``<--`` read), byte count, hex and the
bytes as escaped text, e.g. ``/dev/ttyUSB0 --> 2 bytes: 4b 78 | "Kx"``.
"""

from __future__ import annotations

import logging

trace_logger = logging.getLogger("scopelink.links.trace")

_TEXT_ESCAPES = {
    ord("\r"): "\\r",
    ord("\n"): "\\n",
    ord("\t"): "\\t",
    ord("\\"): "\\\\",
    ord('"'): '\\"',
}


def escape_text(data: bytes) -> str:
    """Printable ASCII as is, common controls as ``\\r \\n \\t``, anything else as ``\\xHH``."""
    return "".join(
        _TEXT_ESCAPES.get(byte) or (chr(byte) if 0x20 <= byte < 0x7F else f"\\x{byte:02x}")
        for byte in data
    )


def format_transfer(direction: str, link_name: str, data: bytes) -> str:
    """The trace line for one transfer of ``data`` over ``link_name`` in ``direction``."""
    return f'{link_name} {direction} {len(data)} bytes: {data.hex(" ")} | "{escape_text(data)}"'


def trace_transfer(direction: str, link_name: str, data: bytes) -> None:
    """Log one transfer at DEBUG level; costs one level check when tracing is off."""
    if trace_logger.isEnabledFor(logging.DEBUG):
        trace_logger.debug("%s", format_transfer(direction, link_name, data))
