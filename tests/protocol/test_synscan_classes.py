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
from scopelink.protocol.synscan.passthrough import TYPED_PASSTHROUGH

SAMPLES: tuple[synscan.AnyCommand, ...] = (
    *(synscan.GetRaDec(precise) for precise in (False, True)),
    *(synscan.GetAzAlt(precise) for precise in (False, True)),
    synscan.GotoRaDec.from_hours_degrees(5.5, -20.25, precise=False),
    synscan.GotoRaDec.from_hours_degrees(23.99, 89.5),
    synscan.SyncRaDec.from_hours_degrees(0.0, -89.0, precise=False),
    synscan.SyncRaDec(0xFFFFFF00, 0x00000100),
    synscan.GotoAzAlt.from_degrees(359.0, -5.0, precise=False),
    synscan.GotoAzAlt(0x12345600, 0xC0000000),
    synscan.GetTrackingMode(),
    synscan.SetTrackingMode(0x23),
    synscan.VariableRateSlew(synscan.Axis.AZM_RA, True, 0x2323),
    synscan.VariableRateSlew.from_arcsec_per_second(synscan.Axis.ALT_DEC, -15.04),
    synscan.FixedRateSlew(synscan.Axis.ALT_DEC, False, 9),
    synscan.FixedRateSlew(synscan.Axis.AZM_RA, True, 0),
    synscan.GetDeviceVersion(synscan.Axis.ALT_DEC),
    synscan.SlowGoto.from_degrees(synscan.Axis.AZM_RA, 180.0),
    synscan.SetAxisPosition(synscan.Axis.ALT_DEC, 0x232323),
    synscan.Passthrough(bytes((1, 16, 3, 0, 0, 0, 3))),
    synscan.Passthrough(b"#######"),
    synscan.GetLocation(),
    synscan.SetLocation(synscan.Location.from_degrees(-33.9, -151.2)),
    synscan.GetTime(),
    synscan.SetTime(
        synscan.DateTime.from_datetime(dt.datetime(2026, 11, 24, 23, 59, 58, tzinfo=dt.UTC))
    ),
    synscan.GetVersion(),
    synscan.GetModel(),
    synscan.Echo(0x23),
    synscan.IsAligned(),
    synscan.IsGotoInProgress(),
    synscan.CancelGoto(),
    synscan.GetPointingState(),
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
def test_each_command_class_round_trips_through_its_own_frame(command: synscan.AnyCommand) -> None:
    frame = command.encode()
    assert len(frame) == synscan.FRAME_LENGTHS[frame[0]] == type(command).frames[frame[0]]
    assert type(command).decode(frame) == command
    assert synscan.decode_command_frame(frame) == command
    assert synscan.encode_command(command) == frame


def test_the_samples_cover_every_command_class() -> None:
    assert {type(command) for command in SAMPLES} == set(synscan.COMMANDS)


def test_every_command_and_reply_class_is_in_the_derived_tables() -> None:
    assert set(_concrete_subclasses(synscan.Command)) == set(synscan.COMMANDS)
    assert set(_concrete_subclasses(synscan.Reply)) == set(synscan.REPLIES)
    assert set(_concrete_subclasses(synscan.PassthroughCommand)) == {
        *TYPED_PASSTHROUGH,
        synscan.Passthrough,
    }
    for name in (
        *(cls.__name__ for cls in synscan.COMMANDS),
        *(cls.__name__ for cls in synscan.REPLIES),
    ):
        assert name in synscan.__all__


def test_the_frame_table_is_exactly_the_classes_letters() -> None:
    letters = {first: length for cls in synscan.COMMANDS for first, length in cls.frames.items()}
    assert letters == synscan.FRAME_LENGTHS
    assert bytes(sorted(synscan.FRAME_LENGTHS)) == b"BEHJKLMPRSTVWZbehmprstwz"


def test_a_frame_decodes_to_exactly_one_class() -> None:
    for cls in synscan.COMMANDS:
        for first, length in cls.frames.items():
            frame = bytes((first,)) + bytes(length - 1)  # zeros: a valid payload for most
            claimed = [other for other in synscan.COMMANDS if first in other.frames]
            decoded = [other.decode(frame) for other in claimed]
            assert sum(isinstance(d, synscan.Command) for d in decoded) <= 1, (frame, decoded)


def _sample_reply(command: synscan.AnyCommand) -> synscan.Reply:
    """A reply the hand control may send to ``command``."""
    if isinstance(command, synscan.GetRaDec | synscan.GetAzAlt):
        return synscan.Position(
            command.coordinates, 0x1234 << 8 if command.precise else 0x1234, 0, command.precise
        )
    if isinstance(command, synscan.Echo):
        return synscan.EchoReply(command.value)
    if isinstance(command, synscan.PassthroughCommand):
        return command.success_reply(bytes(range(command.reply_length)))
    return _FIXED_REPLIES.get(type(command), synscan.Ack())


_FIXED_REPLIES: dict[type[synscan.Command], synscan.AnyReply] = {
    synscan.GetTrackingMode: synscan.TrackingModeReply(2),
    synscan.GetLocation: synscan.Location.from_degrees(51.5, -0.1),
    synscan.GetTime: synscan.DateTime(12, 0, 0, 6, 21, 2026, -5, True),
    synscan.GetVersion: synscan.Version(4, 39, 5),
    synscan.GetModel: synscan.Model(0x23),
    synscan.IsAligned: synscan.Aligned(True),
    synscan.IsGotoInProgress: synscan.GotoInProgress(False),
    synscan.GetPointingState: synscan.PointingState(synscan.PointingSide.WEST),
}


@pytest.mark.parametrize("command", SAMPLES, ids=repr)
def test_each_command_reads_its_own_reply_by_its_own_shape(command: synscan.AnyCommand) -> None:
    reply = _sample_reply(command)
    data = reply.encode()
    assert len(data) in command.reply_shape().lengths
    for cut in range(len(data)):
        assert command.scan_reply(data[:cut]) is synscan.NEED_DATA
    assert command.scan_reply(data + b"extra") == synscan.Complete(reply, len(data))
    assert synscan.parse_reply(command, data) == reply
    if isinstance(command, synscan.PassthroughCommand):
        failed = synscan.PassthroughFailed(data[:-1], 0x01)
        assert len(failed.encode()) in command.reply_shape().lengths
        assert synscan.parse_reply(command, failed.encode()) == failed


class _NamingHandler:
    """Answers every command with the name of the handler method it was dispatched to."""

    def __getattr__(self, name: str) -> Callable[[synscan.AnyCommand], str]:
        return lambda command: name


def _snake(name: str) -> str:
    return re.sub(r"(?<!^)(?=[A-Z])", "_", name).lower()


@pytest.mark.parametrize("command", SAMPLES, ids=repr)
def test_each_command_dispatches_to_the_handler_method_named_after_it(
    command: synscan.AnyCommand,
) -> None:
    handler = cast(synscan.CommandHandler[str], _NamingHandler())
    assert synscan.dispatch(command, handler) == _snake(type(command).__name__)


def test_the_handler_protocol_has_one_method_per_command_class() -> None:
    protocol_methods = {name for name in vars(synscan.CommandHandler) if not name.startswith("_")}
    assert protocol_methods == {cls.handler_name for cls in synscan.COMMANDS}
    assert len(protocol_methods) == len(synscan.COMMANDS)


def test_exactly_the_commands_that_move_or_set_something_change_the_mount() -> None:
    """What a read-only server refuses (answering a plain '#')."""
    assert {cls for cls in synscan.COMMANDS if cls.changes_mount} == {
        synscan.GotoRaDec,
        synscan.GotoAzAlt,
        synscan.SyncRaDec,
        synscan.SetTrackingMode,
        synscan.FixedRateSlew,
        synscan.VariableRateSlew,
        synscan.SlowGoto,
        synscan.SetAxisPosition,
        synscan.SetLocation,
        synscan.SetTime,
        synscan.CancelGoto,
    }
