"""The Sky Tracker's PC port as a UART: 9600 baud only, and no receive buffer.

Two effects of the real port are modelled for bytes coming from the PC (see
``docs/emulators-skytracker.md``, "Line fidelity"):

* **Framing.** On a pty we can read the client's line settings. A byte sent at another baud rate,
  or with other data bits or parity, is re-sampled bit by bit by a 9600 8N1 receiver
  (:func:`resample`), so it arrives garbled as on a real wire. Replies are re-sampled the other
  way, as the client's UART would see them.
* **Overrun.** The firmware needs 11 bit-times from the start of one character to the start of
  the next (the spec asks senders for two stop bits). :class:`StrictReceiver` drops a character
  that starts sooner.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scopelink.links import LineSettings

BAUDRATE = 9600
DEVICE_LINE = LineSettings(baudrate=BAUDRATE, data_bits=8, parity="N", stop_bits=1)
"""The device's own UART: it sends 8N1 and samples one stop bit."""
REQUIRED_BITS_BETWEEN_STARTS = 11
"""Bit-times the firmware needs between the starts of two characters (8N2 spacing)."""
DEFAULT_JITTER_ALLOWANCE_S = 0.005
"""Links without line settings (TCP, memory): how far arrivals may run ahead of the 8N2
schedule before characters are lost. Absorbs transport and event-loop jitter of paced senders."""

_BIT_EPSILON = 1e-9


def _frame_bits(byte: int, line: LineSettings) -> list[int]:
    data = [(byte >> bit) & 1 for bit in range(line.data_bits)]
    parity: list[int] = []
    if line.parity != "N":
        ones = sum(data)
        parity = [ones % 2 if line.parity == "E" else 1 - ones % 2]
    return [0, *data, *parity, *[1] * line.stop_bits]


def framings_match(sender: LineSettings, receiver: LineSettings) -> bool:
    """Whether bytes pass unchanged: same rate, data bits and parity (stop bits do not matter
    to the receiver, which samples one)."""
    return (
        sender.baudrate == receiver.baudrate
        and sender.data_bits == receiver.data_bits
        and sender.parity == receiver.parity
    )


def resample(data: bytes, sender: LineSettings, receiver: LineSettings) -> bytes:
    """What ``receiver`` reads when ``sender`` sends ``data`` back to back on one wire.

    The receiver hunts for a falling edge, samples each bit in its middle at its own rate and
    keeps the byte even on a framing error (the Sky Tracker firmware has no error handling we
    know of). A sender with no known rate (``baudrate=None``) delivers nothing readable.
    """
    if framings_match(sender, receiver):
        return data
    if sender.baudrate is None or receiver.baudrate is None:
        return b""
    levels = [bit for byte in data for bit in _frame_bits(byte, sender)]
    sender_bit_s = 1.0 / sender.baudrate
    receiver_bit_s = 1.0 / receiver.baudrate
    end_s = len(levels) * sender_bit_s

    def level_at(t: float) -> int:
        index = math.floor(t / sender_bit_s + _BIT_EPSILON)
        return levels[index] if 0 <= index < len(levels) else 1

    received = bytearray()
    t = 0.0
    step = sender_bit_s / 16
    while t < end_s:
        if level_at(t) == 1:
            t += step
            continue
        # Start bit found at t: sample data bits in their middles.
        value = 0
        for bit in range(receiver.data_bits):
            value |= level_at(t + (1.5 + bit) * receiver_bit_s) << bit
        received.append(value & 0xFF)
        parity_bits = receiver.parity != "N"
        t += (1.5 + receiver.data_bits + parity_bits) * receiver_bit_s
        # Hunt for the next start bit only once the line has gone idle (high) again.
        while t < end_s and level_at(t) == 0:
            t += step
    return bytes(received)


@dataclass(slots=True)
class StrictReceiver:
    """Drops characters the unbuffered port would lose (call :meth:`receive` per arrival).

    With the sender's line settings known (a pty), bytes that arrived together are placed back to
    back on a reconstructed wire at the sender's framing, and a character starting less than
    11 bit-times after the previous one is lost: an 8N1 burst keeps only its first character,
    an 8N2 burst keeps everything. Without line settings (TCP, memory), each character must keep
    to an 8N2 schedule within ``jitter_allowance_s``; one that runs further ahead is lost.
    """

    jitter_allowance_s: float = DEFAULT_JITTER_ALLOWANCE_S
    _previous_start_s: float = -math.inf
    _ready_at_s: float = -math.inf
    lost: int = 0
    """Characters dropped so far."""

    def receive(self, chunk: bytes, arrival_s: float, sender: LineSettings | None) -> bytes:
        """The characters of ``chunk`` (arrived at ``arrival_s``, monotonic) the device reads."""
        required_s = REQUIRED_BITS_BETWEEN_STARTS / BAUDRATE
        kept = bytearray()
        if sender is None or sender.baudrate is None:
            for byte in chunk:
                if arrival_s >= self._ready_at_s - self.jitter_allowance_s:
                    kept.append(byte)
                    self._ready_at_s = max(arrival_s, self._ready_at_s) + required_s
                else:
                    self.lost += 1
            return bytes(kept)
        frame_s = sender.bits_per_byte / sender.baudrate
        for byte in chunk:
            start_s = max(arrival_s - frame_s, self._previous_start_s + frame_s)
            if start_s - self._previous_start_s >= required_s - _BIT_EPSILON:
                kept.append(byte)
            else:
                self.lost += 1
            self._previous_start_s = start_s
        return bytes(kept)
