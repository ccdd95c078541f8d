"""How log records reach the person at the terminal (docs/cli.md, "Messages").

Without ``-v`` only warnings and errors are shown, each as one sentence: ``scopelink: warning:
the mount's clock is 3 s off`` — no time stamp, no logger name, no traceback (a traceback
attached to a record is dropped; ``-v`` shows it). With ``-v`` every record is shown as a
programmer wants it: time, logger name and message, tracebacks included.
"""

from __future__ import annotations

import logging

__all__ = ["configure_logging"]

VERBOSE_FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s"


class PlainLines(logging.Formatter):
    """``scopelink: warning: MESSAGE`` (or ``error:``), one line, nothing for programmers. A
    record below warning reaches it only from a logger turned up on purpose (a device command's
    ``-v`` turns up the byte trace alone): it keeps the full form, logger name included."""

    def __init__(self) -> None:
        super().__init__(VERBOSE_FORMAT)

    def format(self, record: logging.LogRecord) -> str:
        if record.levelno < logging.WARNING:
            return super().format(record)
        label = "error" if record.levelno >= logging.ERROR else "warning"
        message = " ".join(record.getMessage().split())  # one line, whatever it was given
        return f"scopelink: {label}: {message}"


def configure_logging(verbose: int) -> None:
    """Plain warnings by default; with ``verbose`` every record, in full."""
    handler = logging.StreamHandler()
    handler.setFormatter(PlainLines() if not verbose else logging.Formatter(VERBOSE_FORMAT))
    logging.basicConfig(level=logging.DEBUG if verbose else logging.WARNING, handlers=[handler])
