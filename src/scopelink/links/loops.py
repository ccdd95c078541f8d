"""The event loop a long-running session runs on: uvloop where it is installed, else asyncio's.

uvloop (libuv under a C event loop, the loop uvicorn runs on) takes about a third less CPU per
command than asyncio's default loop for our SynScan driver (``docs/benchmarks.md``, "SynScan
driver"), so ``scopelink serve`` runs on it. ``SCOPELINK_EVENT_LOOP`` chooses:

- ``auto`` (the default): uvloop when it can be imported, else asyncio's default loop (Windows,
  PyPy, or an install without it);
- ``uvloop``: uvloop, or a clear error where it is not installed;
- ``asyncio``: asyncio's default loop (to rule the loop out when something misbehaves).

uvloop's timers and ``loop.time()`` count whole milliseconds (a timer may fire up to a
millisecond before or after its time by ``time.monotonic()``); asyncio's default loop's fire up
to a millisecond late, never early. Nothing ``serve`` runs needs finer timers (the decision and
what was checked: ``docs/serve.md``, "Event loop"). The emulators keep
:func:`~scopelink.links.pacing.precise_event_loop`, whose timers keep time to 0.1 ms.

uvloop is imported only when a loop is chosen: the one-shot commands never pay for it.
"""

from __future__ import annotations

import asyncio
import importlib
import os
import selectors
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

__all__ = [
    "DEFAULT_EVENT_LOOP",
    "EVENT_LOOP_CHOICES",
    "EVENT_LOOP_ENV_VAR",
    "EventLoopChoice",
    "EventLoopChoiceError",
    "choose_event_loop",
    "describe_loop",
    "serve_event_loop",
]

EVENT_LOOP_ENV_VAR: Final = "SCOPELINK_EVENT_LOOP"
"""The environment variable that chooses the loop of ``serve`` (and ``track``)."""
EVENT_LOOP_CHOICES: Final = ("auto", "uvloop", "asyncio")
DEFAULT_EVENT_LOOP: Final = "auto"
"""uvloop where installed, else asyncio's default loop."""


class EventLoopChoiceError(ValueError):
    """``SCOPELINK_EVENT_LOOP`` names no loop, or one that is not installed: a one-line
    message (the CLI adds its hint)."""


@dataclass(frozen=True, slots=True)
class EventLoopChoice:
    """The loop chosen, and why: ``factory`` makes one (for ``asyncio.Runner(loop_factory=)``);
    ``label`` says which before one runs (e.g. ``uvloop 0.21.0``, or ``asyncio (uvloop is not
    installed)``); :func:`describe_loop` says which one runs."""

    name: str
    """``uvloop`` or ``asyncio``."""
    factory: Callable[[], asyncio.AbstractEventLoop]
    version: str = ""
    """uvloop's version (empty for asyncio's loop)."""
    reason: str = ""
    """Why not uvloop, for asyncio's loop: told, or not installed."""

    @property
    def label(self) -> str:
        if self.name == "uvloop":
            return f"uvloop {self.version}"
        return f"asyncio ({self.reason})" if self.reason else "asyncio"


def choose_event_loop(setting: str | None = None) -> EventLoopChoice:
    """The loop ``setting`` (default: ``$SCOPELINK_EVENT_LOOP``, else ``auto``) names;
    :class:`EventLoopChoiceError` for a value not in :data:`EVENT_LOOP_CHOICES` or ``uvloop``
    where it cannot be imported."""
    if setting is None:
        setting = os.environ.get(EVENT_LOOP_ENV_VAR, "")
    value = setting.strip().lower() or DEFAULT_EVENT_LOOP
    if value not in EVENT_LOOP_CHOICES:
        raise EventLoopChoiceError(
            f"{EVENT_LOOP_ENV_VAR}={setting!r} is not one of {', '.join(EVENT_LOOP_CHOICES)}"
        )
    if value == "asyncio":
        return EventLoopChoice("asyncio", _asyncio_loop, reason=f"{EVENT_LOOP_ENV_VAR}=asyncio")
    try:
        uvloop = importlib.import_module("uvloop")
    except ImportError as error:
        if value == "uvloop":
            raise EventLoopChoiceError(
                f"{EVENT_LOOP_ENV_VAR}=uvloop but uvloop cannot be imported ({error})"
            ) from None
        return EventLoopChoice("asyncio", _asyncio_loop, reason="uvloop is not installed")
    factory: Callable[[], asyncio.AbstractEventLoop] = uvloop.new_event_loop
    return EventLoopChoice("uvloop", factory, version=str(uvloop.__version__))


def serve_event_loop() -> asyncio.AbstractEventLoop:
    """A new loop of the kind ``scopelink serve`` runs on (:func:`choose_event_loop`), for
    ``asyncio.Runner(loop_factory=serve_event_loop)``: what the benchmarks measure."""
    return choose_event_loop().factory()


def _asyncio_loop() -> asyncio.AbstractEventLoop:
    """asyncio's default loop (``epoll`` on Linux, the proactor on Windows)."""
    return asyncio.new_event_loop()


def describe_loop(loop: asyncio.AbstractEventLoop, reason: str = "") -> str:
    """What ``loop`` is, as ``serve`` prints it: ``uvloop 0.21.0``, or ``asyncio (epoll)`` with
    ``reason`` (why not uvloop) after the selector: ``asyncio (epoll; uvloop is not installed)``."""
    module = sys.modules.get(type(loop).__module__.partition(".")[0])
    if module is not None and module.__name__ == "uvloop":
        return f"uvloop {module.__version__}"
    selector = getattr(loop, "_selector", None)
    if isinstance(selector, selectors.BaseSelector):
        kind = type(selector).__name__.removesuffix("Selector").lower()
    else:
        kind = type(loop).__name__.lstrip("_")
    return f"asyncio ({kind}; {reason})" if reason else f"asyncio ({kind})"
