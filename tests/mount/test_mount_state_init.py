"""``MountState`` is built through its slots' own descriptors (``mount.frozen_init``: one state
per poll, issue #14): the same signature, defaults, default factory, equality, hash, repr and
frozenness as the dataclass's own ``__init__``, with ``dataclasses.replace`` and positional
calls alike; a class it cannot serve is refused."""

from __future__ import annotations

import dataclasses
import inspect
import time
from datetime import UTC, datetime
from typing import Any

import pytest

from scopelink.mount import MountState, TrackingMode
from scopelink.mount.frozen_init import fast_frozen_init

WHEN = datetime(2026, 11, 25, 4, 0, tzinfo=UTC)


_Plain = dataclasses.make_dataclass(
    "_Plain",
    [
        (
            f.name,
            f.type,
            dataclasses.field(
                default=f.default, default_factory=f.default_factory, compare=f.compare
            ),
        )
        for f in dataclasses.fields(MountState)
    ],
    frozen=True,
    slots=True,
)
"""MountState's fields as the dataclass's own ``__init__`` sets them (the reference)."""


def _values(state: object) -> dict[str, Any]:
    return {f.name: getattr(state, f.name) for f in dataclasses.fields(MountState)}


def test_a_state_is_what_the_dataclass_s_own_init_makes() -> None:
    before = time.monotonic()
    default = MountState(WHEN)
    assert before <= default.received_s <= time.monotonic()  # the factory, called per state
    reference = _Plain(WHEN, received_s=default.received_s)
    assert _values(default) == _values(reference)

    given: dict[str, Any] = {"connected": True, "alt_deg": 12.5, "tracking": TrackingMode.SIDEREAL}
    full = MountState(WHEN, problems=("a",), received_s=3.0, position_received_s=2.0, **given)
    assert _values(full) == _values(
        _Plain(WHEN, problems=("a",), received_s=3.0, position_received_s=2.0, **given)
    )
    positional = MountState(*(_values(full).values()))
    assert _values(positional) == _values(full)
    assert positional == full
    assert hash(positional) == hash(full)
    assert repr(full).startswith("MountState(read_at=")

    replaced = dataclasses.replace(full, alt_deg=13.0)
    assert replaced.alt_deg == 13.0
    assert replaced.received_s == 3.0  # replace keeps the stamp (a republished reading ages)
    with pytest.raises(dataclasses.FrozenInstanceError):
        full.alt_deg = 1.0  # type: ignore[misc]
    with pytest.raises(TypeError, match="read_at"):
        MountState()  # type: ignore[call-arg]
    with pytest.raises(TypeError, match="unexpected keyword"):
        MountState(WHEN, altitude=1.0)  # type: ignore[call-arg]
    assert list(inspect.signature(MountState).parameters) == list(MountState.__match_args__)


def test_what_the_fast_init_cannot_serve_is_refused() -> None:
    @dataclasses.dataclass(slots=True)
    class Mutable:
        x: int

    @dataclasses.dataclass(frozen=True, slots=True)
    class Checked:
        x: int

        def __post_init__(self) -> None:
            pass

    @dataclasses.dataclass(frozen=True, slots=True)
    class KeywordOnly:
        x: int = dataclasses.field(kw_only=True)

    for cls in (Mutable, Checked, KeywordOnly):
        with pytest.raises(TypeError):
            fast_frozen_init(cls)
