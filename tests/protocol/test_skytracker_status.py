"""The ``R`` status byte: spec Table 1 high nibble, NOTES.md low nibble, odd combinations."""

from __future__ import annotations

import pytest

from scopelink.protocol.skytracker import Direction, ModeFlag, TrackerMode, TrackerStatus


@pytest.mark.parametrize(
    ("mode", "byte"),
    [
        (TrackerMode.UTILITY, 0b1000_0000),
        (TrackerMode.TRACK, 0b0000_0000),
        (TrackerMode.GUIDE, 0b0010_0000),
        (TrackerMode.STANDBY, 0b0100_0000),
        (TrackerMode.GOTO, 0b0001_0000),
    ],
)
def test_table_1_mode_bits(mode: TrackerMode, byte: int) -> None:
    status = TrackerStatus.for_mode(mode)
    assert status.to_byte() == byte
    assert TrackerStatus.from_byte(byte).mode is mode
    assert mode.value in "UTDBG"


@pytest.mark.parametrize(
    ("direction", "bit"),
    [(Direction.UP, 3), (Direction.DOWN, 2), (Direction.LEFT, 1), (Direction.RIGHT, 0)],
)
def test_direction_nibble_b3_up_b2_down_b1_left_b0_right(direction: Direction, bit: int) -> None:
    status = TrackerStatus.from_byte(0x20 | 1 << bit)
    assert status.directions == direction
    assert status.mode is TrackerMode.GUIDE


def test_combined_directions() -> None:
    status = TrackerStatus.for_mode(TrackerMode.TRACK, Direction.LEFT | Direction.DOWN)
    assert status.to_byte() == 0x06
    assert "down+left" in status.describe()


def test_every_byte_decodes_without_raising_and_round_trips() -> None:
    for byte in range(256):
        status = TrackerStatus.from_byte(byte)
        assert status.to_byte() == byte
        assert status.describe().startswith(f"0x{byte:02X}: ")


def test_flag_combinations_outside_table_1_keep_their_bits_and_say_so() -> None:
    status = TrackerStatus.from_byte(0x90)
    assert status.mode is None
    assert status.flags == ModeFlag.UTIL | ModeFlag.GOTO
    assert str(status) == "0x90: UTIL|GOTO (not a mode of spec Table 1); pressed: none"


def test_description_in_plain_words() -> None:
    status = TrackerStatus.for_mode(TrackerMode.GUIDE, Direction.UP)
    assert status.describe() == (
        "0x28: GUIDE (SPEED: tracking; arrows move at the guide speed); pressed: up"
    )
    assert "opposite" in TrackerStatus.from_byte(0x0C).describe()


def test_from_byte_refuses_values_that_are_not_bytes() -> None:
    with pytest.raises(ValueError, match="0-255"):
        TrackerStatus.from_byte(256)
