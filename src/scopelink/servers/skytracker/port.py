"""A device's serial port on any link: 9600-baud replies, the client's framing, faults, overruns."""

from __future__ import annotations

import time

from scopelink.links import LineSettings, Link, PtyLink, paced
from scopelink.servers.faults import FaultInjector

from .line import BAUDRATE, DEFAULT_JITTER_ALLOWANCE_S, DEVICE_LINE, StrictReceiver, resample

DEVICE_BITS_PER_BYTE = DEVICE_LINE.bits_per_byte


class DevicePort:
    """The device end of ``link``.

    Replies leave at 9600 baud 8N1 (``pace``). On a pty the client's line settings are honoured
    both ways: a wrong rate, data size or parity garbles the bytes. With ``strict`` the port
    also loses characters that come faster than the firmware reads them (see ``line.py``).
    """

    def __init__(
        self,
        link: Link,
        *,
        faults: FaultInjector | None = None,
        pace: bool = True,
        strict: bool = False,
        jitter_allowance_s: float = DEFAULT_JITTER_ALLOWANCE_S,
    ) -> None:
        self.link = link
        self.faults = faults if faults is not None else FaultInjector()
        self._output: Link = paced(link, BAUDRATE, DEVICE_BITS_PER_BYTE) if pace else link
        self.receiver = StrictReceiver(jitter_allowance_s) if strict else None

    def client_line(self) -> LineSettings | None:
        """The client's line settings when the link can tell (a pty), else None."""
        return self.link.line_settings() if isinstance(self.link, PtyLink) else None

    async def read(self) -> bytes:
        """The next bytes the device's UART reads (possibly empty when all were lost)."""
        await self.faults.wait_until_reading()
        # Through the pacer: it notes when a command arrived, so the reply cannot start earlier.
        chunk = await self._output.read()
        arrival_s = time.monotonic()
        client = self.client_line()
        if client is not None:
            chunk = resample(chunk, client, DEVICE_LINE)
        if self.receiver is not None:
            chunk = self.receiver.receive(chunk, arrival_s, client)
        return chunk

    async def reply(self, command_key: str, data: bytes) -> bool:
        """Answer the command ``command_key`` with ``data`` (possibly empty), faults applied.

        Returns False when a fault closed the link.
        """
        fault = self.faults.select(command_key)
        client = self.client_line()
        if client is not None:
            data = resample(data, DEVICE_LINE, client)
        if not data and fault is None:
            return True
        return await self.faults.deliver(self._output, data, fault)

    async def write(self, data: bytes) -> None:
        """Send bytes that answer no command of ours (relayed from the bus), no faults."""
        client = self.client_line()
        if client is not None:
            data = resample(data, DEVICE_LINE, client)
        await self._output.write(data)
