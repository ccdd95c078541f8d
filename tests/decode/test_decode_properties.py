"""Properties of the annotator on any bytes: it never raises and accounts for every byte once."""

from __future__ import annotations

import contextlib
import io

from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.cli.main import main
from scopelink.decode import Annotation, Chunk, Direction, Kind, Protocol, annotate

# Bytes that mean something to one of the protocols, so random traces reach deep states.
_MEANINGFUL = b"eEzZrRsSbBtTKVJLMPpWwHhmQAqGUDuldNO#\r 0123456789ABCDEF,.+-\x00\x01\x02\x10\x11\x24"
_BYTES = st.lists(
    st.one_of(st.sampled_from(list(_MEANINGFUL)), st.integers(0, 255)), max_size=80
).map(bytes)
_PROTOCOLS = st.sampled_from(list(Protocol))
_DIRECTIONS = st.sampled_from([Direction.PC, Direction.DEVICE, None])
_CHUNKS = st.lists(st.builds(Chunk, _BYTES, _DIRECTIONS, st.booleans()), max_size=8)

_SETTINGS = settings(max_examples=150, deadline=None)


def _with_bytes(annotations: list[Annotation]) -> list[Annotation]:
    return [annotation for annotation in annotations if annotation.data]


@_SETTINGS
@given(_BYTES, _PROTOCOLS)
def test_untagged_annotations_cover_every_byte_once_in_order(
    trace: bytes, protocol: Protocol
) -> None:
    annotations = annotate(trace, protocol)
    position = 0
    for annotation in _with_bytes(annotations):
        assert annotation.offset == position
        position += len(annotation.data)
    assert position == len(trace)
    assert all(0 <= a.offset <= len(trace) for a in annotations)
    commands = {a.offset for a in annotations if a.kind is Kind.COMMAND}
    for annotation in annotations:
        if annotation.error_offset is not None:
            assert annotation.offset <= annotation.error_offset < position
        if annotation.kind is Kind.REPLY:
            assert annotation.answers in commands
        if annotation.answers is not None:
            assert annotation.answers < annotation.offset or not annotation.data


@_SETTINGS
@given(_CHUNKS, _PROTOCOLS)
def test_tagged_annotations_cover_each_direction_once(
    chunks: list[Chunk], protocol: Protocol
) -> None:
    annotations = annotate(chunks, protocol)
    sent: dict[Direction, bytearray] = {Direction.PC: bytearray(), Direction.DEVICE: bytearray()}
    annotated: dict[Direction, bytearray] = {
        Direction.PC: bytearray(),
        Direction.DEVICE: bytearray(),
    }
    total = sum(len(chunk.data) for chunk in chunks)
    for annotation in _with_bytes(annotations):
        annotated[annotation.direction] += annotation.data
    for annotation in annotations:
        assert 0 <= annotation.offset <= total
    assert sum(len(data) for data in annotated.values()) == total
    if all(chunk.direction is not None for chunk in chunks):
        for chunk in chunks:
            assert chunk.direction is not None
            sent[chunk.direction] += chunk.data
        assert annotated == sent


@_SETTINGS
@given(_BYTES, _PROTOCOLS, st.data())
def test_untagged_chunking_does_not_matter(
    trace: bytes, protocol: Protocol, data: st.DataObject
) -> None:
    cuts = sorted(data.draw(st.lists(st.integers(0, len(trace)), max_size=6)))
    pieces = [trace[start:end] for start, end in zip([0, *cuts], [*cuts, len(trace)], strict=True)]
    assert annotate([Chunk(piece) for piece in pieces], protocol) == annotate(trace, protocol)


@settings(max_examples=60, deadline=None)
@given(_BYTES, _PROTOCOLS)
def test_the_command_renders_any_trace(trace: bytes, protocol: Protocol) -> None:
    output = io.StringIO()
    with contextlib.redirect_stdout(output), contextlib.redirect_stderr(io.StringIO()):
        status = main(["decode", "--protocol", protocol.value, "--hex", trace.hex() or "00"])
    assert status in (0, 1)
    assert output.getvalue()
