"""What every fuzz target shares: the `Target` record, the chunking, the invariant helpers, the
one event loop and the scratch folder."""

from __future__ import annotations

import asyncio
import os
import random
import tempfile
import typing
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path


class FuzzFailureError(AssertionError):
    """A parser broke one of its invariants on this input."""


def expect(condition: bool, message: str) -> None:
    if not condition:
        raise FuzzFailureError(message)


@dataclass(frozen=True, slots=True)
class Target:
    name: str
    seeds: tuple[bytes, ...]
    """Valid inputs; the generator mutates, splices and concatenates them."""
    check: Callable[[bytes, random.Random], None]
    tokens: bytes = b""
    """Bytes that mean something to this parser (delimiters, command letters), inserted more
    often."""
    max_size: int = 256
    share: float = 1.0
    """This target's inputs relative to a parser's (devices answer in real time: fewer inputs)."""


def chunks(data: bytes, rng: random.Random) -> Iterator[bytes]:
    """``data`` cut where ``rng`` says: whole, a few random cuts, or byte by byte."""
    style = rng.random()
    if style < 0.3 or len(data) < 2:
        yield data
        return
    if style < 0.4:
        yield from (data[index : index + 1] for index in range(len(data)))
        return
    cuts = sorted(rng.sample(range(1, len(data)), min(len(data) - 1, rng.randint(1, 4))))
    start = 0
    for cut in [*cuts, len(data)]:
        yield data[start:cut]
        start = cut


class _Parser(typing.Protocol):
    def receive_data(self, data: bytes) -> None: ...

    def next_event(self) -> object: ...


def parsed_in_chunks(
    parser: _Parser, stream: bytes, rng: random.Random, need_data: object
) -> list[typing.Any]:
    """Every event ``parser`` yields for ``stream`` fed in :func:`chunks`."""
    events = []
    for chunk in chunks(stream, rng):
        parser.receive_data(chunk)
        while (event := parser.next_event()) is not need_data:
            events.append(event)
    return events


def checked_events(
    parser: _Parser,
    stream: bytes,
    rng: random.Random,
    need_data: object,
    allowed: tuple[type, ...],
) -> list[object]:
    """Every event ``parser`` yields for ``stream`` fed in :func:`chunks`, each of an
    ``allowed`` type, and no more of them than the bytes allow (:func:`progress_guard`)."""
    events: list[object] = []
    for chunk in chunks(stream, rng):
        parser.receive_data(chunk)
        while (event := parser.next_event()) is not need_data:
            events.append(event)
            progress_guard(len(events), len(stream))
            expect(isinstance(event, allowed), f"unexpected event {event!r}")
    return events


def progress_guard(count: int, fed: int) -> None:
    # Each event consumes at least one byte; a few more (a pause, a release) are allowed for.
    expect(count <= fed + 4, f"{count} events from {fed} bytes: the parser does not advance")


SCRATCH_DIR = Path(tempfile.gettempdir()) / f"scopelink-fuzz-{os.getpid()}"
"""Files the targets write (the settings file, the devices' data), one folder per run."""

_LOOP: list[asyncio.AbstractEventLoop] = []


def event_loop() -> asyncio.AbstractEventLoop:
    """The one event loop the targets that need one run on, for the whole run."""
    if not _LOOP:
        _LOOP.append(asyncio.new_event_loop())
    return _LOOP[0]
