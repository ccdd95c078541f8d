"""The SynScan server: bytes from a link in, one reply per command out, in order.

A :class:`SynScanServer` serves any number of links (each with its own command stream) in front of
one :class:`~scopelink.servers.synscan.device.SynScanHandControl`. Commands are handled one at a
time, as the hand control does: while it waits (latency, a delayed reply) later bytes wait in the
link. Faults from a :class:`~scopelink.servers.faults.FaultInjector` apply per command.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Awaitable, Callable
from contextlib import AbstractAsyncContextManager

from scopelink.links import Link, LinkClosedError
from scopelink.protocol.synscan import (
    NEED_DATA,
    Ack,
    AnyCommand,
    AnyReply,
    ServerError,
    SynScanServerConnection,
)
from scopelink.servers.access import AccessControl, current_client
from scopelink.servers.faults import FaultInjector, FaultKind
from scopelink.servers.synscan.device import NoReply, SynScanHandControl

__all__ = ["PARTIAL_FRAME_TIMEOUT_S", "SynScanServer"]

logger = logging.getLogger(__name__)

PARTIAL_FRAME_TIMEOUT_S = 1.0
"""An incomplete command older than this is dropped (a whole 18-byte command takes 19 ms)."""

_NOT_EXECUTED = frozenset({FaultKind.STALL, FaultKind.HALT, FaultKind.CLOSE})
"""Faults that stand for a hung device: the command is not carried out. Under the others the
device works and only its reply goes wrong on the way."""


def command_key(command: AnyCommand) -> str:
    """The key faults match a command by: its first byte as text (``e``, ``P``, ``K``...)."""
    return chr(command.encode()[0])


class SynScanServer:
    """Serves the SynScan protocol for ``hand_control`` on every link given to :meth:`serve`.

    :attr:`access` (no limits unless replaced) makes it read-only; a TCP client's commands wait
    for their turn under its rate (admission itself is the hosting device's).
    """

    def __init__(
        self,
        hand_control: SynScanHandControl,
        faults: FaultInjector | None = None,
        *,
        access: AccessControl | None = None,
        dead_man: bool = False,
    ):
        self.hand_control = hand_control
        self.faults = faults or FaultInjector()
        self.access = access if access is not None else AccessControl(name="SynScan")
        self.dead_man = dead_man
        """Stop a rate slew a client started when its link goes (``scopelink serve`` turns it on
        for phone apps; off in the device emulator, since a hand control on a cable cannot
        notice)."""

    async def serve(self, link: Link) -> None:
        """Answer commands from ``link`` until it closes (or a ``close`` fault closes it)."""
        dead_man: AbstractAsyncContextManager[object] = contextlib.nullcontext()
        if self.dead_man:
            dead_man = self.hand_control.mount.motion_client(f"SynScan client {link.name}")
        async with dead_man:
            await self._serve_link(link)

    async def _serve_link(self, link: Link) -> None:
        connection = SynScanServerConnection()
        client = current_client()
        try:
            while True:
                await self.faults.wait_until_reading()
                data = await self._read(link, connection)
                if data is None:
                    dropped = connection.discard_partial()
                    logger.info("%s: incomplete command %r dropped", link.name, dropped)
                    continue
                connection.receive_data(data)
                if not await self._answer_all(link, connection, client.throttle):
                    return
        except LinkClosedError as exc:
            logger.info("%s: %s", link.name, exc)

    async def _read(self, link: Link, connection: SynScanServerConnection) -> bytes | None:
        """The next bytes; None when a partial command has waited too long for the rest."""
        if not connection.parser.pending:
            return await link.read()
        try:
            async with asyncio.timeout(PARTIAL_FRAME_TIMEOUT_S):
                return await link.read()
        except TimeoutError:
            return None

    async def _answer_all(
        self,
        link: Link,
        connection: SynScanServerConnection,
        throttle: Callable[[], Awaitable[None]],
    ) -> bool:
        """Answer every complete command received; False once the link was closed by a fault."""
        while True:
            await self.faults.wait_until_reading()
            event = connection.next_event()
            if event is NEED_DATA:
                return True
            if isinstance(event, ServerError):
                logger.info("%s: %s", link.name, event.describe())
                continue
            fault = self.faults.select(command_key(event))
            if fault is not None and fault.kind in _NOT_EXECUTED:
                connection.skip_reply()
                if fault.kind is FaultKind.CLOSE:
                    await link.close()
                    return False
                continue
            await throttle()
            if self.access.read_only and event.changes_mount:
                # the hand control's answer to a command it refuses is a plain '#' with nothing
                # done (what it sends for a goto below the horizon), so that is the refusal;
                # a raw Passthrough is already answered as unanswerable over a Mount
                logger.info("%s: read-only: %s refused", link.name, event.describe())
                reply: AnyReply = Ack()
            else:
                try:
                    reply = await self.hand_control.answer(event)
                except NoReply as silence:  # nothing current to answer with, as a hung device
                    logger.info("%s: %s", link.name, silence)
                    connection.skip_reply()
                    continue
            if self.hand_control.config.latency_s:
                await asyncio.sleep(self.hand_control.config.latency_s)
            if not await self.faults.deliver(link, connection.send(reply), fault):
                return False
