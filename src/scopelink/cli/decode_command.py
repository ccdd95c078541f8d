"""``scopelink decode``: annotate a byte trace of either protocol (see docs/decode.md)."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from typing import Any, Final

from scopelink.cli.commands import CommandParsers
from scopelink.cli.errors import CommandError
from scopelink.decode import (
    Annotation,
    Chunk,
    Direction,
    Kind,
    Peer,
    Protocol,
    TraceInputError,
    annotate,
    escape_bytes,
    parse_trace,
)
from scopelink.decode.recording import Recording, RecordingError, is_recording, read_recording

_ARROWS: Final = {Direction.PC: "->", Direction.DEVICE: "<-"}
_PEER_TAGS: Final = {Peer.SYNSCAN: "", Peer.SKY_TRACKER: "[ST] ", Peer.SKY_COMMANDER: "[SC] "}
_KIND_PREFIXES: Final = {
    Kind.COMMAND: "",
    Kind.REPLY: "",
    Kind.NOTE: "note: ",
    Kind.ERROR: "error: ",
}
_RAW_COLUMN_MAX: Final = 24
_CONTEXT_BYTES: Final = 16
_INDENT: Final = " " * 12


def register(commands: CommandParsers) -> None:
    """Add the ``decode`` subcommand."""
    parser = commands.parser(
        "decode",
        description=(
            "Annotate a byte trace: each command and reply with its meaning in plain units. "
            "Each argument (or input line) is one chunk of escaped text (\\r \\n \\t \\0 \\xNN "
            "\\\\) or, with --hex, of hex bytes; it may start with a direction tag (> or -> or "
            "TX: or PC: from the computer; < or <- or RX: or HC: ST: SC: from the device). "
            "Untagged bytes are one stream in time order: a command, then its reply. Lines of "
            "an INDI debug log (CMD <...> / RES <...>) are read as such. Exit status 1 if the "
            "trace has an error."
        ),
    )
    parser.add_argument("chunks", nargs="*", metavar="BYTES", help="trace chunks, in time order")
    parser.add_argument(
        "--protocol",
        choices=[protocol.value for protocol in Protocol],
        default=None,
        help="what the trace holds: synscan (default; a recording's own protocol for a "
        "recording); skytracker (the Sky Commander behind its bus); skycommander (alone on its "
        "port)",
    )
    parser.add_argument(
        "--file",
        metavar="PATH",
        help="read the trace from a file, one chunk a line ('-': stdin), or a recording "
        "('scopelink record'; also given alone as BYTES)",
    )
    parser.add_argument("--hex", action="store_true", help="chunks are hex bytes, not text")
    parser.add_argument(
        "--raw", action="store_true", help="--file holds the bytes themselves (one stream)"
    )
    parser.add_argument("--json", action="store_true", help="one JSON object per message")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Read the trace, annotate it, print the annotations; 1 if the trace has an error."""
    recording = _recording(args)
    if recording is not None:
        chunks = recording.chunks()
        recorded = recording.protocol
        args.protocol = args.protocol or (recorded.value if recorded else None)
    else:
        chunks = _read_chunks(args)
    args.protocol = args.protocol or Protocol.SYNSCAN.value
    annotations = annotate(chunks, Protocol(args.protocol))
    if args.json:
        for annotation in annotations:
            print(json.dumps(_as_json(annotation), ensure_ascii=False))
    else:
        trace = b"".join(chunk.data for chunk in chunks)
        _print_text(annotations, trace, hex_output=args.hex, show_peer=args.protocol != "synscan")
    errors = sum(annotation.is_error for annotation in annotations)
    if errors:
        print(
            f"scopelink decode: {errors} error{'s' if errors > 1 else ''} in the trace",
            file=sys.stderr,
        )
        if any(_looks_like_a_path(chunk) for chunk in args.chunks):
            print("  hint: to decode a file, give --file PATH", file=sys.stderr)
    return 1 if errors else 0


def _looks_like_a_path(chunk: str) -> bool:
    """A BYTES argument that is more likely a file someone meant to decode."""
    return chunk.startswith(("/", "./", "../", "~/")) or os.path.isfile(chunk)


# ------------------------------------------------------------------------------------------ input


def _recording(args: argparse.Namespace) -> Recording | None:
    """The recording ``--file`` names, or the one BYTES argument naming a recording file."""
    if args.file is not None and args.file != "-" and not (args.raw or args.hex or args.chunks):
        path = args.file
    elif args.file is None and len(args.chunks) == 1 and os.path.isfile(args.chunks[0]):
        path = args.chunks[0]
    else:
        return None
    data = _read_file(path)
    if not is_recording(data):
        return None
    try:
        return read_recording(data)
    except RecordingError as error:
        raise CommandError(f"{path}: {error}") from None


def _read_chunks(args: argparse.Namespace) -> list[Chunk]:
    if args.file is not None and args.chunks:
        raise CommandError("give the trace as arguments or with --file, not both")
    if args.raw and args.file is None:
        raise CommandError("--raw reads a file", hint="add --file PATH (or --file - for stdin)")
    if args.file is not None:
        data = _read_file(args.file)
        if args.raw:
            return [Chunk(data)]
        items = [data]
    elif args.chunks:
        items = [os.fsencode(chunk) for chunk in args.chunks]
    else:
        raise CommandError(
            "nothing to decode",
            hint="give bytes as arguments, e.g. scopelink decode e '34AB0500,12CE0500#', "
            "or --file PATH",
        )
    try:
        return parse_trace(items, hex_input=args.hex)
    except TraceInputError as error:
        shown = escape_bytes(error.line[: error.column])
        raise CommandError(
            f"cannot read the trace: {error.reason}\n"
            f"{_INDENT}{escape_bytes(error.line)}\n{_INDENT}{' ' * len(shown)}^",
            hint="escapes are \\r \\n \\t \\0 \\xNN \\\\; "
            "--hex takes bytes like '65 33' or '0x65,0x33'",
        ) from None


def _read_file(path: str) -> bytes:
    if path == "-":
        return sys.stdin.buffer.read()
    try:
        with open(path, "rb") as file:
            return file.read()
    except OSError as error:
        raise CommandError(f"cannot read {path}: {error.strerror}") from None


# ----------------------------------------------------------------------------------------- output


def _show(data: bytes, hex_output: bool) -> str:
    return data.hex(" ").upper() if hex_output else escape_bytes(data)


def _print_text(
    annotations: Sequence[Annotation], trace: bytes, *, hex_output: bool, show_peer: bool
) -> None:
    width = min(
        _RAW_COLUMN_MAX, max((len(_show(a.data, hex_output)) for a in annotations), default=0)
    )
    previous: Annotation | None = None
    for annotation in annotations:
        raw = _show(annotation.data, hex_output) if annotation.data else "(none)"
        peer = _PEER_TAGS[annotation.peer] if show_peer else ""
        answers = annotation.answers
        # A reply right after its command needs no pointer; a pipelined one does.
        follows = previous is not None and previous.offset == answers
        to = "" if answers is None or follows else f" (answers {answers})"
        print(
            f"{annotation.offset:>6}  {_ARROWS[annotation.direction]}  {raw:<{width}}  "
            f"{peer}{_KIND_PREFIXES[annotation.kind]}{annotation.meaning}{to}"
        )
        previous = annotation
        if annotation.error_offset is not None:
            print(_caret_lines(trace, annotation.error_offset, hex_output))


def _caret_lines(trace: bytes, offset: int, hex_output: bool) -> str:
    """The trace around byte ``offset``, with a caret under it."""
    start = max(0, offset - _CONTEXT_BYTES)
    end = min(len(trace), offset + _CONTEXT_BYTES + 1)
    before = "..." if start else ""
    after = "..." if end < len(trace) else ""
    separator = " " if hex_output else ""
    pieces = [_show(trace[index : index + 1], hex_output) for index in range(start, end)]
    lead = len(before) + sum(len(piece) + len(separator) for piece in pieces[: offset - start])
    where = f" byte {offset}" if hex_output else ""
    return f"{_INDENT}{before}{separator.join(pieces)}{after}\n{_INDENT}{' ' * lead}^{where}"


def _as_json(annotation: Annotation) -> dict[str, Any]:
    return {
        "offset": annotation.offset,
        "direction": annotation.direction.value,
        "peer": annotation.peer.value,
        "kind": annotation.kind.value,
        "hex": annotation.data.hex(" ").upper(),
        "text": escape_bytes(annotation.data),
        "meaning": annotation.meaning,
        "error_offset": annotation.error_offset,
        "answers": annotation.answers,
        "message": type(annotation.message).__name__ if annotation.message is not None else None,
    }
