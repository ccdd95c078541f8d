"""scopelink's pytest plugin: emulated SynScan, Sky Tracker and Sky Commander devices as fixtures.

Registered by the wheel's ``pytest11`` entry point, so any project where scopelink is installed
has it. Fixtures (each a started :class:`~scopelink.testing.handle.EmulatorHandle`, stopped after
the test):

- ``synscan_emulator``: a SynScan hand control in front of a simulated mount;
- ``skytracker_emulator``: the Sky Tracker motor box with its Sky Commander on the bus;
- ``skycommander_emulator``: the Sky Commander alone on its port;
- ``scopelink_emulator_factory``: ``factory("synscan", model="AZ-GTi", ...)`` starts one more
  each time it is called (several devices in one test).

Their parameters (:class:`~scopelink.testing.options.EmulatorSpec`) come from the marker
``@pytest.mark.scopelink_emulator(transport="pty", clock_rate=10, ...)`` on the test, its class
or module, or from indirect parametrization (``indirect=True`` with a dict). A parameter no such
device can have fails the test's setup with one line. See docs/testing-with-scopelink.md.

This module imports nothing of scopelink until a fixture is used: pytest imports it at every start.
"""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from scopelink.testing.handle import EmulatorHandle

MARKER = "scopelink_emulator"
"""The marker that carries the emulator fixtures' parameters."""


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        f"{MARKER}(**options): parameters of scopelink's emulator fixtures (transport, model, "
        "model_code, firmware, aligned, site, faults, seed, clock_rate, start, pacing, data_dir)",
    )


def _options(request: pytest.FixtureRequest, device: str) -> dict[str, Any]:
    options: dict[str, Any] = {}
    for marker in reversed(list(request.node.iter_markers(MARKER))):  # closest wins
        if marker.args:
            pytest.fail(f"{MARKER} takes keywords only, not {marker.args!r}", pytrace=False)
        options.update(marker.kwargs)
    param = getattr(request, "param", None)
    if isinstance(param, dict):
        options.update(param)
    elif param is not None:
        pytest.fail(f"{device}_emulator: parametrize it with a dict, not {param!r}", pytrace=False)
    if "device" in options:
        pytest.fail(f"{MARKER}: the fixture names the device; leave out device=", pytrace=False)
    return options


def start_emulator(device: str, options: dict[str, Any]) -> EmulatorHandle:
    """A started handle for ``device`` with ``options``; a bad option fails the test in one line."""
    from scopelink.testing.handle import EmulatorHandle  # noqa: PLC0415 - only when used
    from scopelink.testing.options import EmulatorSpec, EmulatorSpecError  # noqa: PLC0415

    known = {field.name for field in dataclasses.fields(EmulatorSpec)}
    for name in options:
        if name not in known:
            close = difflib.get_close_matches(name, sorted(known), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            pytest.fail(f"{MARKER}: no option {name!r}{hint}", pytrace=False)
    try:
        spec = EmulatorSpec(device=device, **options)
    except EmulatorSpecError as error:
        refusal = f"{device} emulator: {error}"
    else:
        return EmulatorHandle(spec).start()
    pytest.fail(refusal, pytrace=False)  # outside the except: no chained exception is shown


def _fixture(request: pytest.FixtureRequest, device: str) -> Iterator[EmulatorHandle]:
    handle = start_emulator(device, _options(request, device))
    try:
        yield handle
    finally:
        handle.close()


@pytest.fixture
def synscan_emulator(request: pytest.FixtureRequest) -> Iterator[EmulatorHandle]:
    """A SynScan hand control (EQ6, firmware 4.39.05 unless the marker says otherwise)."""
    yield from _fixture(request, "synscan")


@pytest.fixture
def skytracker_emulator(request: pytest.FixtureRequest) -> Iterator[EmulatorHandle]:
    """The Sky Tracker motor box with its Sky Commander on the bus."""
    yield from _fixture(request, "skytracker")


@pytest.fixture
def skycommander_emulator(request: pytest.FixtureRequest) -> Iterator[EmulatorHandle]:
    """The Sky Commander alone on its port."""
    yield from _fixture(request, "skycommander")


@pytest.fixture
def scopelink_emulator_factory(
    request: pytest.FixtureRequest,
) -> Iterator[Callable[..., EmulatorHandle]]:
    """``factory(device, **options)``: start another emulator; all stop after the test. The
    marker's options apply first, the call's over them."""
    started: list[EmulatorHandle] = []

    def factory(device: str = "synscan", **options: Any) -> EmulatorHandle:
        handle = start_emulator(device, {**_options(request, device), **options})
        started.append(handle)
        return handle

    try:
        yield factory
    finally:
        for handle in reversed(started):
            handle.close()
