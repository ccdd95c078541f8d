"""The Sky Tracker driver's state: one poll (``R`` status, then the position through the bus
unless a GOTO keeps it), explicit reads of position and status, waiting for a GOTO to end.
"""

from __future__ import annotations

import asyncio
import logging
import time

from scopelink.links import LinkError
from scopelink.mount import DeviceError, MountError, MountState, NotConnectedError
from scopelink.mount.scheduling import Priority
from scopelink.protocol.skytracker import (
    ReadPosition,
    ReadStatus,
    Reply,
    StatusReply,
    TrackerMode,
    TrackerStatus,
)

from .base import pointing_of
from .connection import SkyTrackerConnection
from .exchange import BusRefusedError, SkyTrackerLine

__all__ = ["SkyTrackerPolling"]

logger = logging.getLogger(__name__)

GOTO_STATUS_POLL_S = 0.05
"""Status polls during a GOTO (by wait_for_goto, and the poller's refreshes) are this far apart."""

_GOTO = TrackerMode.GOTO
_POLL = Priority.POLL
"""Enum members looked up once: each look-up of ``TrackerMode.GOTO`` costs ~80 ns (Python 3.11)."""
_READ_STATUS = ReadStatus()
_READ_POSITION = (ReadPosition(),)
_ONE_RETRY = (0.0,)
"""A poll's commands and its one immediate bus retry, built once (every poll sends them)."""


class SkyTrackerPolling(SkyTrackerConnection):
    """Read the state (see :class:`SkyTrackerMount`)."""

    async def refresh(self) -> MountState:
        """``R`` status; then, unless a GOTO keeps the bus, the position through the bus.

        A lost link (closed, or the box silent longer than ``stale_after_s``) reads as not
        connected; while engaged, the next refresh opens it anew and identifies the box again.
        """
        line = self._line
        if line is None or line.link.closed or self._link_lost:  # _needs_reconnect(), inline
            await self._reconnect_for_poll()
            line = self._require_line()
        if self._mode is _GOTO:
            # During a GOTO a poll is one status byte (the bus is refused): back-to-back polls
            # would read it hundreds of times a second; GOTO_STATUS_POLL_S apart is plenty.
            since = time.monotonic() - self._goto_status_at
            if since < GOTO_STATUS_POLL_S:
                await asyncio.sleep(GOTO_STATUS_POLL_S - since)
        try:
            reply = await line.ask(_READ_STATUS, _POLL)
            # The status check (_read_status), its common case inline: a reading equal to the
            # driver's record is trusted at once; any other is read again until two agree.
            if type(reply) is not StatusReply or reply.status != self._status:
                reply = await self._read_status(line, _POLL, first=reply)
            self._note_status(reply, line.last_answer_s)
            self._goto_status_at = line.last_answer_s
            if self._mode is not _GOTO and self._commander_present is not False:
                # The position: one immediate retry after a garbled or missing grant; a refusal
                # means a GOTO began since the status read (the position is then kept).
                try:
                    (position,) = await line.commander(
                        _READ_POSITION, _POLL, retry_delays_s=_ONE_RETRY
                    )
                except BusRefusedError as error:
                    if error.unanswered:
                        raise
                    self._mode = _GOTO
                else:
                    received_s = line.last_answer_s
                    self._position = pointing_of(position, self._clock(), self._site, received_s)
                    if self._commander_present is None:  # answering again after a fault
                        self._commander_present = True
        except (DeviceError, NotConnectedError) as error:
            self._problems = (str(error),)
            silent_s = time.monotonic() - line.last_answer_s
            if line.link.closed or silent_s > self.stale_after_s:
                # The link is gone (or the box silent): so is the connection, until reopened.
                if not self._link_lost:
                    logger.warning("the Sky Tracker on %s is lost: %s", self.spec, error)
                self._link_lost = True
            self._publish_now()
            raise
        self._problems = ()
        return self._publish_now()

    async def _reconnect_for_poll(self) -> None:
        """Reopen a lost line while engaged (one reconnection at a time, whoever asks)."""
        try:
            await self._reconnection.run_if(
                lambda: self._engaged and self._needs_reconnect(), self._reconnect
            )
        except (MountError, LinkError) as error:
            self._problems = (f"reconnecting: {error}",)
            self._link_lost = True
            self._publish_now()
            raise

    async def read_position(self) -> tuple[float, float]:
        """J2000 (RA hours, Dec degrees) from the Sky Commander now, backing off on refusals."""
        position = await self._read_position(self._require_line(), Priority.COMMAND, retry=True)
        self._publish_now()
        return position.ra_j2000_hours, position.dec_j2000_deg

    async def read_status(self) -> TrackerStatus:
        """``R``: the box's mode flags and pressed arrows now."""
        self._note_status(await self._read_status(self._require_line(), Priority.COMMAND))
        assert self._status is not None
        return self._status

    async def _read_status(
        self, line: SkyTrackerLine, priority: Priority, *, first: Reply | None = None
    ) -> Reply:
        """``R``; a status other than the driver's record is read again (the byte has no
        redundancy). The record is asked after every reading: the driver's own presses (the
        custom-rate loop's, a move, a pulse) change the pressed arrows and the mode between two
        readings, and each leaves its confirmed status as the record."""

        def recorded() -> Reply | None:
            return StatusReply(self._status) if self._status is not None else None

        return await self._read_agreed(line, _READ_STATUS, priority, first=first, known=recorded)

    async def wait_for_goto(self, timeout_s: float | None = None) -> MountState:
        """Poll ``R`` until the GOTO bit clears (TRACK follows), then refresh everything."""
        async with asyncio.timeout(timeout_s):
            while (await self.read_status()).mode is TrackerMode.GOTO:  # noqa: ASYNC110
                await asyncio.sleep(GOTO_STATUS_POLL_S)
        return await self.refresh()
