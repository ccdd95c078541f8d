"""A device that answers from a recording (``scopelink emulate synscan --replay FILE``).

The recording's exchanges (what the computer sent, then what the device answered) are played
in order, byte for byte and for any protocol: once the bytes a client sends match the next
exchange's command, the recorded reply is sent. A byte that is not the one recorded at that
point is a **divergence**: it is reported (on stderr by the CLI, in :attr:`ReplayDevice.divergences`
for tests) with the recording's line and the byte's position, dropped, and not answered; the
replay stays where it was, so a client that retries or goes on as recorded is answered again
(a retry may begin with the very byte that broke the match: ``K`` then ``Ka`` is answered).
Replies go out at once (at 9600 baud when paced), not at the recorded latency.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from scopelink.astro import Site
from scopelink.decode import escape_bytes
from scopelink.decode.recording import Exchange, Recording, read_recording
from scopelink.links import Link
from scopelink.mount import Identity, MountState
from scopelink.servers.hosting import HostedDevice, WireSpeed

__all__ = ["Divergence", "ReplayDevice", "ReplayResult", "load_recording", "replay_to_driver"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class Divergence:
    """Bytes a client sent that the recording does not have at that point."""

    line: int | None
    """The recording's line of the exchange expected (None: past the end of the recording)."""
    exchange: int
    """Index of that exchange (0-based)."""
    offset: int
    """Position of the first unexpected byte within that exchange's command."""
    expected: bytes
    """What the recording has from that position (b"" past the end)."""
    received: bytes

    def describe(self) -> str:
        got = escape_bytes(self.received)
        if self.line is None:
            return f"replay: received '{got}' after the end of the recording; not answered"
        return (
            f"replay: divergence at line {self.line} (exchange {self.exchange + 1}, byte "
            f"{self.offset}): expected '{escape_bytes(self.expected)}', received '{got}'; "
            "not answered"
        )


def load_recording(path: str | Path) -> Recording:
    """Read a recording file; OSError or RecordingError (a ValueError) naming the line."""
    return read_recording(Path(path).read_bytes())


class ReplayDevice(HostedDevice):
    """Serves a recording on a pty, TCP port or memory pair (see the module docstring)."""

    def __init__(
        self,
        recording: Recording,
        *,
        wire: WireSpeed | None = None,
        report: Callable[[Divergence], None] | None = None,
    ) -> None:
        super().__init__(self._serve, wire=wire)
        self.recording = recording
        self._exchanges: list[Exchange] = recording.exchanges()
        self._index = 0
        self._matched = 0
        self._diverge_at = 0
        self._report = report
        self.divergences: list[Divergence] = []
        """Every divergence, in order."""
        self.replies_sent = 0

    @property
    def exchanges_played(self) -> int:
        """How many recorded exchanges were answered (or passed: a command with no reply)."""
        return self._index

    @property
    def finished(self) -> bool:
        """Whether every recorded exchange was played."""
        return self._index >= len(self._exchanges)

    async def _serve(self, link: Link) -> None:
        await self._answer_if_due(link)  # a reply recorded before any command
        while True:
            data = await link.read()
            diverging = bytearray()
            for byte in data:
                if self.finished:
                    diverging.append(byte)
                    continue
                command = self._exchanges[self._index].command
                if byte == command[self._matched]:
                    self._flush(diverging)
                    self._matched += 1
                    await self._answer_if_due(link)
                elif restart := _restart(command, self._matched, byte):
                    # A command cut short and sent again (a client's retry): this byte is the
                    # divergence where it stands, and with what came before it begins the
                    # command afresh.
                    self._diverge_at = self._matched
                    self._flush(bytearray((byte,)))
                    self._matched = restart
                    await self._answer_if_due(link)
                else:
                    if not diverging:
                        self._diverge_at = self._matched
                    diverging.append(byte)
                    self._matched = 0  # a command cut short: wait for it from its start again
            self._flush(diverging)

    async def _answer_if_due(self, link: Link) -> None:
        while not self.finished:
            exchange = self._exchanges[self._index]
            if self._matched < len(exchange.command):
                return
            if exchange.reply:
                await link.write(exchange.reply)
                self.replies_sent += 1
            self._index += 1
            self._matched = 0

    def _flush(self, diverging: bytearray) -> None:
        if not diverging:
            return
        if self.finished:
            divergence = Divergence(None, len(self._exchanges), 0, b"", bytes(diverging))
        else:
            exchange = self._exchanges[self._index]
            divergence = Divergence(
                exchange.line,
                self._index,
                self._diverge_at,
                exchange.command[self._diverge_at :],
                bytes(diverging),
            )
        diverging.clear()
        self.divergences.append(divergence)
        logger.info("%s", divergence.describe())
        if self._report is not None:
            self._report(divergence)


def _restart(command: bytes, matched: int, byte: int) -> int:
    """How much of ``command`` the bytes seen end with, once ``byte`` broke a match of
    ``matched`` bytes (0: none)."""
    seen = command[:matched] + bytes((byte,))
    for length in range(matched, 0, -1):
        if seen.endswith(command[:length]):
            return length
    return 0


@dataclass(frozen=True, slots=True)
class ReplayResult:
    """What scopelink's driver made of a recorded device (:func:`replay_to_driver`)."""

    identity: Identity
    state: MountState
    divergences: tuple[Divergence, ...]
    exchanges_played: int
    exchanges_recorded: int


async def replay_to_driver(path: str | Path, *, site: Site | None = None) -> ReplayResult:
    """Connect scopelink's driver for the recording's protocol to the recording (on a pty), as
    ``scopelink info`` does, and disconnect: a regression test of a recorded session in one
    call (docs/cli.md, "Record and replay"). The recording must hold a session scopelink's own
    driver began (record ``scopelink info``, ``status``...); its protocol must be named."""
    from scopelink.drivers.open import DeviceSpec, create_mount  # noqa: PLC0415 - if used

    recording = load_recording(path)
    if recording.protocol is None:
        raise ValueError(
            f"{path}: the recording names no protocol (record with --device KIND:LINK)"
        )
    device = ReplayDevice(recording)
    async with device:
        where = await device.on_pty()
        spec = DeviceSpec(recording.protocol.value, where)
        mount = create_mount(spec, site=site or Site(0.0, 0.0))
        await mount.connect()
        try:
            identity, state = mount.identity, mount.state
        finally:
            await mount.disconnect()
    return ReplayResult(
        identity,
        state,
        tuple(device.divergences),
        device.exchanges_played,
        len(recording.exchanges()),
    )
