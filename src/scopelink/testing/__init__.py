"""Emulators for other projects' tests: a thread-backed handle and a pytest plugin.

``from scopelink.testing import EmulatorHandle, EmulatorSpec``; the plugin
(:mod:`scopelink.testing.plugin`, registered as pytest's ``scopelink`` plugin by the package's
``pytest11`` entry point) gives the fixtures. See docs/testing-with-scopelink.md.

The names load when first used, so that pytest's start (which imports the plugin in every project
where scopelink is installed) does not pay for the emulators.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from scopelink.testing.handle import EmulatorHandle
    from scopelink.testing.options import EmulatorSpec, EmulatorSpecError
    from scopelink.testing.recording import CommandLog, Received

__all__ = ["CommandLog", "EmulatorHandle", "EmulatorSpec", "EmulatorSpecError", "Received"]

_HOMES = {
    "EmulatorHandle": "handle",
    "EmulatorSpec": "options",
    "EmulatorSpecError": "options",
    "CommandLog": "recording",
    "Received": "recording",
}


def __getattr__(name: str) -> object:
    if name in _HOMES:
        return getattr(importlib.import_module(f"scopelink.testing.{_HOMES[name]}"), name)
    raise AttributeError(f"module 'scopelink.testing' has no attribute {name!r}")
