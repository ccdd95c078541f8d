"""The Sky Tracker driver's connection: open the link and identify the box (``V``, ``k``, ``R``,
a position through the bus), release arrows a broken link left pressed, reconnect a lost link,
and the calibration rule (``S`` only as the first command after power-on).
"""

from __future__ import annotations

import contextlib
import logging

from scopelink.links import Link, LinkError
from scopelink.mount import DeviceError, NotConnectedError
from scopelink.mount.scheduling import Priority
from scopelink.protocol.skytracker import (
    Acknowledge,
    CalibrationReply,
    GuideSpeedReply,
    ReadCalibration,
    ReadGuideSpeed,
    ReadStatus,
    ReadVersion,
    ReleaseDirections,
    SetCalibration,
    TrackerMode,
    VersionReply,
)
from scopelink.protocol.skytracker.calfloat import encode_calfloat_pair

from .base import SkyTrackerBase
from .calibration import CalibrationFactors, CalibrationRuleError
from .exchange import (
    BadReplyError,
    BusRefusedError,
    LineOutOfSyncError,
    ReplyTimeoutError,
    SkyTrackerLine,
)

__all__ = ["SkyTrackerConnection"]

logger = logging.getLogger(__name__)


class SkyTrackerConnection(SkyTrackerBase):
    """Open, identify, reconnect; calibration (see :class:`SkyTrackerMount`)."""

    def _needs_reconnect(self) -> bool:
        return self._line is None or self._line.link.closed or self._link_lost

    async def _drop_line(self) -> None:
        line, self._line = self._line, None
        if line is not None:
            with contextlib.suppress(LinkError):
                await line.link.close()

    async def _reconnect(self) -> None:
        """Open the lost link anew and identify the box again (it may have been switched off
        and on): arrows left pressed by the broken link are released (see connect)."""
        await self._drop_line()
        await self._open_and_identify(None)
        if not self._engaged:  # disconnected meanwhile: let go of the new line
            await self._drop_line()
            self._publish_now()
            raise NotConnectedError(f"the Sky Tracker on {self.spec} was disconnected meanwhile")
        logger.warning("the Sky Tracker on %s answers again: reconnected", self.spec)

    async def _open_and_identify(self, calibration: CalibrationFactors | None) -> None:
        link = await self._open_link()
        line = SkyTrackerLine(
            link, timeout_s=self.timeout_s, bus=self.bus, scheduler=self.scheduler
        )
        self._line = line
        self._held.clear()
        self._cancel_pulses()  # a new line presses no arrow: no pulse is under way on it
        self._rest_mode = None
        try:
            if calibration is not None:
                await self._write_calibration_first(line, calibration)
            self._version = await self._read_version(line)
            speeds = await self._read_agreed(line, ReadGuideSpeed())
            assert isinstance(speeds, GuideSpeedReply)
            self._guide_speeds = (speeds.azimuth_arcsec_per_s, speeds.elevation_arcsec_per_s)
            if self._wanted_guide_speed is not None:
                await self._set_guide_speeds((self._wanted_guide_speed,) * 2)
            self._pulse_speeds = self._guide_speeds
            self._note_status(await self._read_agreed(line, ReadStatus()))
            await self._release_orphaned_arrows(line)
            await self._detect_commander(line)
        except BaseException:
            self._line = None
            with contextlib.suppress(LinkError):
                await link.close()
            raise
        self._problems = ()
        self._link_lost = False
        self._publish_now()

    async def _release_orphaned_arrows(self, line: SkyTrackerLine) -> None:
        """``b`` when the box reports arrows pressed: a motion started over a link that broke
        (or by another program) that nobody on this connection can stop any more. The hand
        box's own arrows stay pressed while its user holds them."""
        assert self._status is not None
        if not self._status.directions:
            return
        logger.warning("arrows still pressed at connect (%s): releasing them", self._status)
        replies = await line.ask_sequence([ReleaseDirections(), ReadStatus()])
        self._note_status(await self._read_agreed(line, ReadStatus(), first=replies[-1]))

    @staticmethod
    async def _read_version(line: SkyTrackerLine) -> str:
        """``V``, asked twice if need be: a probe by another program (e.g. a SynScan driver's
        ``K`` echo) can leave the box inside a ``K`` or ``S`` frame that swallows the first
        ``V`` as payload; once that frame is complete (or dropped), ``V`` is answered."""
        try:
            reply = await line.ask(ReadVersion())
        except (ReplyTimeoutError, BadReplyError) as error:
            logger.info("no version on the first try, asking again: %s", error)
            reply = await line.ask(ReadVersion())
            # The first answer may only have been late, and so read as the second's: now that
            # the version is known, the resync's sync point reads past any answer still due.
            if not await line.resync():
                raise LineOutOfSyncError(
                    f"the Sky Tracker on {line.link.name} answered 'V' only late and then "
                    "not the sync point: is it busy or off?"
                ) from error
        assert isinstance(reply, VersionReply)
        return reply.text

    async def _open_link(self) -> Link:
        try:
            return await self._open()
        except LinkError as error:
            raise NotConnectedError(f"cannot open the Sky Tracker's link: {error}") from error

    async def _detect_commander(self, line: SkyTrackerLine) -> None:
        if self._mode is TrackerMode.GOTO:
            self._commander_present = None  # the bus is refused during a GOTO; it needs one
            return
        try:
            await self._read_position(line, Priority.COMMAND, retry=False)
        except ReplyTimeoutError as error:
            if self._commander_present:
                # Seen on this mount before the line was lost (a reconnection): a Sky Commander
                # that does not answer yet is a fault the position polls report and retry, not
                # gone for good (that left every position refused as stale while connected).
                logger.warning("the Sky Commander does not answer yet: %s", error)
                self._commander_present = None
                return
            logger.warning("no Sky Commander on the bus: %s", error)
            self._commander_present = False
            return
        except BusRefusedError:
            self._commander_present = None
            return
        self._commander_present = True

    async def read_calibration(self) -> CalibrationFactors:
        """``s``: the motor calibration factors (always allowed)."""
        reply = await self._read_agreed(self._require_line(), ReadCalibration())
        assert isinstance(reply, CalibrationReply)
        return CalibrationFactors(reply.azimuth_factor, reply.elevation_factor)

    async def _write_calibration_first(
        self, line: SkyTrackerLine, factors: CalibrationFactors
    ) -> None:
        if line.statistics.commands_sent:
            raise CalibrationRuleError("'S' must be the first command on the line")
        command = SetCalibration(factors.azimuth_factor, factors.elevation_factor)
        try:
            reply = await line.ask(command)
        except (ReplyTimeoutError, BadReplyError) as error:
            # A refused 'S' gets no reply; so does one whose 'A' was lost. 's' tells them apart.
            logger.info("no good acknowledgement of 'S' (%s): reading the factors back", error)
            # The version is not known yet, so the resync had no sync point: a late 'A' could
            # be read as the first byte of the factors. A whole reply timeout of quiet first.
            try:
                await line.link.drain_input(self.timeout_s, 2 * self.timeout_s)
            except LinkError as link_error:
                raise NotConnectedError(f"the link {line.link.name} failed: {link_error}") from None
            stored = await self._read_agreed(line, ReadCalibration())
            assert isinstance(stored, CalibrationReply)
            wanted = encode_calfloat_pair(command.azimuth_factor, command.elevation_factor)
            if encode_calfloat_pair(stored.azimuth_factor, stored.elevation_factor) == wanted:
                logger.info("'S' was taken (its acknowledgement was lost)")
                return
            raise CalibrationRuleError(
                f"the Sky Tracker did not acknowledge 'S' nor take it ({error}; it still holds "
                f"factors {stored.azimuth_factor:g}, {stored.elevation_factor:g}): it takes "
                "calibration only as the first command after it is switched on, and once, so "
                "something talked to it since power-on (an earlier connection?), or 'S' was lost "
                "on the line: switch it off and on and try again"
            ) from None
        if not isinstance(reply, Acknowledge):
            raise DeviceError(f"unexpected reply to 'S': {reply}")
