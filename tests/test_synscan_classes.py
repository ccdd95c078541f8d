"""Each SynScan command class carries its own wire form, and the codec's tables are derived from
the classes: every class round-trips and no class can be left out of a table."""

from __future__ import annotations

import datetime as dt
import inspect
import re
import sys
from collections.abc import Callable, Iterator
from typing import cast

import pytest

from scopelink.protocol import synscan
from scopelink.protocol.synscan import (
    COMMANDS,
    FRAME_LENGTHS,
    NEED_DATA,
    REPLIES,
    Ack,
    Aligned,
    AnyCommand,
    AnyReply,
    Axis,
    CancelGoto,
    Command,
    CommandHandler,
    Complete,
    DateTime,
    Echo,
    EchoReply,
    FixedRateSlew,
    GetAzAlt,
    GetDeviceVersion,
    GetLocation,
    GetModel,
    GetPointingState,
    GetRaDec,
    GetTime,
    GetTrackingMode,
    GetVersion,
    GotoAzAlt,
    GotoInProgress,
    GotoRaDec,
    IsAligned,
    IsGotoInProgress,
    Location,
    Model,
    Passthrough,
    PassthroughCommand,
    PassthroughFailed,
    PointingSide,
    PointingState,
    Position,
    Reply,
    SetAxisPosition,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SlowGoto,
    SyncRaDec,
    TrackingModeReply,
    VariableRateSlew,
    Version,
    decode_command_frame,
    parse_reply,
)
from scopelink.protocol.synscan.passthrough import TYPED_PASSTHROUGH

SAMPLES: tuple[AnyCommand, ...] = (
    *(GetRaDec(precise) for precise in (False, True)),
    *(GetAzAlt(precise) for precise in (False, True)),
    GotoRaDec.from_hours_degrees(5.5, -20.25, precise=False),
    GotoRaDec.from_hours_degrees(23.99, 89.5),
    SyncRaDec.from_hours_degrees(0.0, -89.0, precise=False),
    SyncRaDec(0xFFFFFF00, 0x00000100),
    GotoAzAlt.from_degrees(359.0, -5.0, precise=False),
    GotoAzAlt(0x12345600, 0xC0000000),
    GetTrackingMode(),
    SetTrackingMode(0x23),
    VariableRateSlew(Axis.AZM_RA, True, 0x2323),
    VariableRateSlew.from_arcsec_per_second(Axis.ALT_DEC, -15.04),
    FixedRateSlew(Axis.ALT_DEC, False, 9),
    FixedRateSlew(Axis.AZM_RA, True, 0),
    GetDeviceVersion(Axis.ALT_DEC),
    SlowGoto.from_degrees(Axis.AZM_RA, 180.0),
    SetAxisPosition(Axis.ALT_DEC, 0x232323),
    Passthrough(bytes((1, 16, 3, 0, 0, 0, 3))),
    Passthrough(b"#######"),
    GetLocation(),
    SetLocation(Location.from_degrees(-33.9, -151.2)),
    GetTime(),
    SetTime(DateTime.from_datetime(dt.datetime(2026, 11, 24, 23, 59, 58, tzinfo=dt.UTC))),
    GetVersion(),
    GetModel(),
    Echo(0x23),
    IsAligned(),
    IsGotoInProgress(),
    CancelGoto(),
    GetPointingState(),
)


def _concrete_subclasses(base: type[object]) -> Iterator[type[object]]:
    """Public, concrete classes below ``base`` that their module names (the ones a user gets)."""
    subclasses: list[type[object]] = base.__subclasses__()
    for cls in subclasses:
        yield from _concrete_subclasses(cls)
        public = not cls.__name__.startswith("_")
        named = getattr(sys.modules[cls.__module__], cls.__name__, None) is cls
        if public and named and not inspect.isabstract(cls):
            yield cls


@pytest.mark.parametrize("command", SAMPLES, ids=repr)
def test_each_command_class_round_trips_through_its_own_frame(command: AnyCommand) -> None:
    frame = command.encode()
    assert len(frame) == FRAME_LENGTHS[frame[0]] == type(command).frames[frame[0]]
    assert type(command).decode(frame) == command
    assert decode_command_frame(frame) == command
    assert synscan.encode_command(command) == frame


def test_the_samples_cover_every_command_class() -> None:
    assert {type(command) for command in SAMPLES} == set(COMMANDS)


def test_every_command_and_reply_class_is_in_the_derived_tables() -> None:
    assert set(_concrete_subclasses(Command)) == set(COMMANDS)
    assert set(_concrete_subclasses(Reply)) == set(REPLIES)
    assert set(_concrete_subclasses(PassthroughCommand)) == {*TYPED_PASSTHROUGH, Passthrough}
    for name in (*(cls.__name__ for cls in COMMANDS), *(cls.__name__ for cls in REPLIES)):
        assert name in synscan.__all__


def test_the_frame_table_is_exactly_the_classes_letters() -> None:
    letters = {first: length for cls in COMMANDS for first, length in cls.frames.items()}
    assert letters == FRAME_LENGTHS
    assert bytes(sorted(FRAME_LENGTHS)) == b"BEHJKLMPRSTVWZbehmprstwz"


def test_a_frame_decodes_to_exactly_one_class() -> None:
    for cls in COMMANDS:
        for first, length in cls.frames.items():
            frame = bytes((first,)) + bytes(length - 1)  # zeros: a valid payload for most
            claimed = [other for other in COMMANDS if first in other.frames]
            decoded = [other.decode(frame) for other in claimed]
            assert sum(isinstance(d, Command) for d in decoded) <= 1, (frame, decoded)


def _sample_reply(command: AnyCommand) -> AnyReply:
    """A reply the hand control may send to ``command``."""
    if isinstance(command, GetRaDec | GetAzAlt):
        return Position(
            command.frame, 0x1234 << 8 if command.precise else 0x1234, 0, command.precise
        )
    if isinstance(command, Echo):
        return EchoReply(command.value)
    if isinstance(command, PassthroughCommand):
        return command.success_reply(bytes(range(command.reply_length)))
    return _FIXED_REPLIES.get(type(command), Ack())


_FIXED_REPLIES: dict[type[Command], AnyReply] = {
    GetTrackingMode: TrackingModeReply(2),
    GetLocation: Location.from_degrees(51.5, -0.1),
    GetTime: DateTime(12, 0, 0, 6, 21, 2026, -5, True),
    GetVersion: Version(4, 39, 5),
    GetModel: Model(0x23),
    IsAligned: Aligned(True),
    IsGotoInProgress: GotoInProgress(False),
    GetPointingState: PointingState(PointingSide.WEST),
}


@pytest.mark.parametrize("command", SAMPLES, ids=repr)
def test_each_command_reads_its_own_reply_by_its_own_shape(command: AnyCommand) -> None:
    reply = _sample_reply(command)
    data = reply.encode()
    assert len(data) in command.reply_shape().lengths
    for cut in range(len(data)):
        assert command.scan_reply(data[:cut]) is NEED_DATA
    assert command.scan_reply(data + b"extra") == Complete(reply, len(data))
    assert parse_reply(command, data) == reply
    if isinstance(command, PassthroughCommand):
        failed = PassthroughFailed(data[:-1], 0x01)
        assert len(failed.encode()) in command.reply_shape().lengths
        assert parse_reply(command, failed.encode()) == failed


class _NamingHandler:
    """Answers every command with the name of the handler method it was dispatched to."""

    def __getattr__(self, name: str) -> Callable[[AnyCommand], str]:
        return lambda command: name


def _snake(name: str) -> str:
    return re.sub(r"(?<!^)(?=[A-Z])", "_", name).lower()


@pytest.mark.parametrize("command", SAMPLES, ids=repr)
def test_each_command_dispatches_to_the_handler_method_named_after_it(command: AnyCommand) -> None:
    handler = cast(CommandHandler[str], _NamingHandler())
    assert command.dispatch(handler) == _snake(type(command).__name__)


def test_the_handler_protocol_has_one_method_per_command_class() -> None:
    protocol_methods = {name for name in vars(CommandHandler) if not name.startswith("_")}
    assert protocol_methods == {_snake(cls.__name__) for cls in COMMANDS}


def test_exactly_the_commands_that_move_or_set_something_change_the_mount() -> None:
    """What a read-only server refuses (answering a plain '#')."""
    assert {cls for cls in COMMANDS if cls.changes_mount} == {
        GotoRaDec,
        GotoAzAlt,
        SyncRaDec,
        SetTrackingMode,
        FixedRateSlew,
        VariableRateSlew,
        SlowGoto,
        SetAxisPosition,
        SetLocation,
        SetTime,
        CancelGoto,
    }
