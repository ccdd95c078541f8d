"""Annotating a SynScan trace: commands framed by `CommandParser`, replies read by shape."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from scopelink.decode.model import Direction, Kind, Peer
from scopelink.decode.session import Session, describe_byte
from scopelink.protocol import synscan
from scopelink.protocol.synscan.angles import HASH
from scopelink.protocol.synscan.message import Complete, Mismatch

_PEER = Peer.SYNSCAN


@dataclass(slots=True)
class _AwaitedReply:
    """A command sent and the bytes of its reply so far."""

    command: synscan.AnyCommand
    command_offset: int
    data: bytearray = field(default_factory=bytearray)
    positions: list[int] = field(default_factory=list)
    mismatch: Mismatch | None = None
    """Set once the reply stopped fitting; its bytes are then collected up to a ``#``."""

    @property
    def longest(self) -> int:
        return max(synscan.reply_shape(self.command).lengths)


class SynScanSession(Session):
    """PC bytes go through the codec's `CommandParser`; each command's reply through
    `scan_reply`.

    A reply that stops fitting is read on up to its ``#`` (at most as long as the longest reply
    the command can have), so that the rest of it is not taken for commands.
    """

    def __init__(self) -> None:
        super().__init__()
        self._parser = synscan.CommandParser()
        self._pc_positions: list[int] = []
        self._pc_base = 0  # parser offset of _pc_positions[0]: annotated bytes are forgotten
        self._annotated_until = 0
        self._awaited: deque[_AwaitedReply] = deque()

    def awaiting_reply(self) -> bool:
        return bool(self._awaited)

    # ------------------------------------------------------------------------------- commands

    def from_pc(self, byte: int, offset: int) -> None:
        self._flush_stray()
        self._parser.receive_data(bytes((byte,)))
        self._pc_positions.append(offset)
        while True:
            event = self._parser.next_frame()
            if event is synscan.NEED_DATA:
                self._note_skipped_hashes(self._parser.offset)
                # Everything before the parser's offset is annotated: a live link (the
                # dashboard's traffic panel) must not keep a position per byte forever.
                del self._pc_positions[: self._parser.offset - self._pc_base]
                self._pc_base = self._parser.offset
                return
            self._note_skipped_hashes(event.offset)
            match event:
                case synscan.ParsedCommand(command, raw, start):
                    self._emit_pc(start, raw, Kind.COMMAND, command.describe(), message=command)
                    self._awaited.append(
                        _AwaitedReply(command, self._pc_positions[start - self._pc_base])
                    )
                case synscan.UnknownCommand(value, start):
                    self._emit_pc(
                        start,
                        bytes((value,)),
                        Kind.ERROR,
                        f"unknown command byte {describe_byte(value)}",
                        error_index=0,
                    )
                case synscan.MalformedCommand(frame, index, start, reason):
                    self._emit_pc(
                        start,
                        frame,
                        Kind.ERROR,
                        f"malformed {chr(frame[0])!r} command: {reason}",
                        error_index=index,
                    )

    def _note_skipped_hashes(self, until: int) -> None:
        """The parser skips a ``#`` before a command silently; the trace says so."""
        for start in range(self._annotated_until, until):
            self._emit_pc(start, b"#", Kind.NOTE, "stray '#' before a command (ignored)")

    def _emit_pc(
        self,
        start: int,
        raw: bytes,
        kind: Kind,
        meaning: str,
        *,
        error_index: int | None = None,
        message: synscan.AnyCommand | None = None,
    ) -> None:
        first = start - self._pc_base
        positions = self._pc_positions[first : first + len(raw)]
        self._emit(
            positions,
            raw,
            kind,
            meaning,
            direction=Direction.PC,
            peer=_PEER,
            error_offset=None if error_index is None else positions[error_index],
            message=message,
        )
        self._annotated_until = start + len(raw)

    # -------------------------------------------------------------------------------- replies

    def from_device(self, byte: int, offset: int) -> None:
        if not self._awaited:
            self._stray_byte(byte, offset, _PEER)
            return
        awaited = self._awaited[0]
        awaited.data.append(byte)
        awaited.positions.append(offset)
        if awaited.mismatch is not None:
            if byte == HASH or len(awaited.data) >= awaited.longest:
                self._emit_bad_reply(awaited.mismatch)
            return
        result = synscan.scan_reply(awaited.command, awaited.data)
        if result is synscan.NEED_DATA:
            return
        if isinstance(result, Complete):
            self._awaited.popleft()
            self._emit(
                awaited.positions,
                bytes(awaited.data),
                Kind.REPLY,
                result.reply.describe(),
                direction=Direction.DEVICE,
                peer=_PEER,
                message=result.reply,
                answers=awaited.command_offset,
            )
            return
        awaited.mismatch = result
        if byte == HASH or len(awaited.data) >= awaited.longest:
            self._emit_bad_reply(result)

    def _emit_bad_reply(self, mismatch: Mismatch) -> None:
        awaited = self._awaited.popleft()
        shape = synscan.reply_shape(awaited.command)
        self._emit(
            awaited.positions,
            bytes(awaited.data),
            Kind.ERROR,
            f"reply to {awaited.command.describe()!r} does not fit: {mismatch.reason} "
            f"(expected {shape.description})",
            direction=Direction.DEVICE,
            peer=_PEER,
            error_offset=awaited.positions[mismatch.index],
            answers=awaited.command_offset,
        )

    def _close_awaited(self, offset: int, why_absent: str, why_cut: str) -> None:
        while self._awaited:
            awaited = self._awaited[0]
            if awaited.mismatch is not None:
                self._emit_bad_reply(awaited.mismatch)
                continue
            self._awaited.popleft()
            if not awaited.data:
                self._note_absent(
                    offset,
                    _PEER,
                    f"no reply to {awaited.command.describe()!r} {why_absent}",
                    awaited.command_offset,
                )
                continue
            shape = synscan.reply_shape(awaited.command)
            self._emit(
                awaited.positions,
                bytes(awaited.data),
                Kind.ERROR,
                f"incomplete reply to {awaited.command.describe()!r}: {len(awaited.data)} bytes "
                f"{why_cut} (expected {shape.description})",
                direction=Direction.DEVICE,
                peer=_PEER,
                error_offset=awaited.positions[-1],
                answers=awaited.command_offset,
            )

    def finish(self, offset: int) -> None:
        self._flush_stray()
        pending = self._parser.pending
        if pending:
            start = self._parser.offset
            length = synscan.frame_length(pending[0])
            self._emit_pc(
                start,
                pending,
                Kind.ERROR,
                f"incomplete {chr(pending[0])!r} command: {len(pending)} of {length} bytes "
                "before the end of the trace",
                error_index=len(pending) - 1,
            )
        self._close_awaited(offset, "in the trace", "before the end of the trace")
