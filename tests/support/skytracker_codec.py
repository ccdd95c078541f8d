"""Shared helpers and strategies for the Sky Tracker / Sky Commander codec tests (no tests here)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any, Protocol

from hypothesis import strategies as st

from scopelink.protocol.skytracker import (
    PAUSED,
    RelayToCommander,
    Wait,
    decode_calfloat,
)


class EventSource(Protocol):
    def receive_data(self, data: bytes) -> None: ...
    def next_event(self) -> Any: ...


def drain(connection: EventSource, on_pause: Callable[[], None] | None = None) -> list[Any]:
    """Every event available now; ``on_pause`` answers a PAUSED (the device deciding a Q)."""
    events: list[Any] = []
    while True:
        event = connection.next_event()
        if event is PAUSED and on_pause is not None:
            on_pause()
            continue
        if isinstance(event, Wait):
            return events
        events.append(event)


def feed(
    connection: EventSource,
    data: bytes,
    cuts: Iterable[int] = (),
    on_pause: Callable[[], None] | None = None,
) -> list[Any]:
    """Feed ``data`` split at ``cuts``, draining after every chunk."""
    events: list[Any] = []
    start = 0
    for cut in [*sorted(set(cuts)), len(data)]:
        connection.receive_data(data[start:cut])
        events += drain(connection, on_pause)
        start = cut
    return events


def merge_relays(events: Sequence[Any]) -> list[Any]:
    """Join consecutive relay events: how relayed bytes are chunked depends on arrival."""
    merged: list[Any] = []
    for event in events:
        if (
            isinstance(event, RelayToCommander)
            and merged
            and isinstance(merged[-1], RelayToCommander)
        ):
            merged[-1] = RelayToCommander(merged[-1].data + event.data)
        else:
            merged.append(event)
    return merged


def wire_length(event: Any) -> int:
    """Bytes of the stream an event stands for."""
    if hasattr(event, "data"):
        return len(event.data)
    return len(event.encode())


canonical_calfloat_bytes = st.one_of(
    st.just(bytes(4)),
    st.builds(
        lambda sign, exponent, fraction: ((sign << 31) | (exponent << 23) | fraction).to_bytes(
            4, "big"
        ),
        st.integers(0, 1),
        st.integers(1, 255),
        st.integers(0, (1 << 23) - 1),
    ),
)
"""Every 4-byte pattern the encoder can produce."""

calfloat_values = canonical_calfloat_bytes.map(decode_calfloat)
"""Numbers exactly representable in the bias-128 format."""


def chunk_cuts(data_size: int) -> st.SearchStrategy[list[int]]:
    return st.lists(st.integers(0, data_size), max_size=12)
