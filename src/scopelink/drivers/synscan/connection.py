"""The SynScan driver's connection: identify the hand control on a fresh link (``V``, ``m``,
motor versions, ``J``, ``w``), reconnect a lost link, tell a lost device from a noisy line.
"""

from __future__ import annotations

import dataclasses
import logging
import time

from scopelink.astro import Site
from scopelink.drivers.synscan.base import SynScanBase
from scopelink.drivers.synscan.identify import HandControlInfo, capabilities_for
from scopelink.mount import DeviceError, NotConnectedError
from scopelink.protocol.synscan import (
    Aligned,
    Axis,
    DeviceVersion,
    GetDeviceVersion,
    GetLocation,
    GetModel,
    GetVersion,
    IsAligned,
    Location,
    Model,
    Version,
    VersionDialect,
)

__all__ = ["SynScanConnection"]

logger = logging.getLogger(__name__)

SITE_TOLERANCE_DEG = 1.0 / 60.0
"""The hand control stores its site to the arcsecond; a difference above an arcminute is real."""


def _site_mismatch(theirs: Location, ours: Site) -> str:
    """Why the hand control's site disagrees with ours, or "" when they agree."""
    longitude_gap = abs((theirs.longitude - ours.longitude_deg + 180.0) % 360.0 - 180.0)
    if (
        abs(theirs.latitude - ours.latitude_deg) <= SITE_TOLERANCE_DEG
        and longitude_gap <= SITE_TOLERANCE_DEG
    ):
        return ""
    return (
        f"the hand control's site ({theirs.latitude:.4f}°, {theirs.longitude:.4f}°) is not the "
        f"configured one ({ours.latitude_deg:.4f}°, {ours.longitude_deg:.4f}°): call set_site "
        "to send ours, or configure the hand control's"
    )


class SynScanConnection(SynScanBase):
    """Identify and reconnect (see :class:`SynScanMount`)."""

    async def _identify(self, *, reopen: bool = True) -> None:
        """Echo on a freshly opened link (``reopen``; else the wire's current one), then ``V``,
        ``m``, motor versions, ``J``, ``w``."""
        if reopen:
            await self.wire.open()
        self._identified_on = self.wire.statistics.reconnects
        version = await self._ask(GetVersion(), Version)
        if version.dialect is VersionDialect.NEXSTAR_BINARY:
            raise DeviceError(
                f"{self.wire.name} answered V like a Celestron NexStar, not a SynScan hand control"
            )
        model = await self._ask(GetModel(), Model)
        # A stale "m" reply (code + '#') must never pass for a resynchronising echo.
        self.wire.avoid_echo.add(model.code)
        motors = (
            await self._motor_version(Axis.AZM_RA),
            await self._motor_version(Axis.ALT_DEC),
        )
        self.info = HandControlInfo(version, model, motors)
        if self.info.old_firmware:
            logger.warning(
                "%s: hand control firmware %s predates the protocol spec (3.38 / 4.38.06)",
                self.wire.name,
                self.info.identity(self.wire.name).firmware,
            )
        self._aligned = (await self._ask(IsAligned(), Aligned)).aligned
        self._site_mismatch = _site_mismatch(await self._ask(GetLocation(), Location), self.site)
        if self._site_mismatch:
            logger.warning("%s: %s", self.wire.name, self._site_mismatch)
        self._identity = self.info.identity(self.wire.name)
        self._capabilities = capabilities_for(self.info)

    async def _reconnect(self) -> None:
        """Open the lost link anew (or take the one the wire reopened by itself) and identify
        the device again: it may have been switched off and on (alignment, site) or be another
        one. Owed stops go out with the first exchange that works (see ``stops.py``)."""
        lost = self._reidentify
        if lost:
            await self.wire.close()
        try:
            await self._identify(reopen=lost)
        except BaseException:
            await self.wire.close()
            raise
        if not self._connected:  # disconnected meanwhile: let go of the new link
            await self.wire.close()
            raise NotConnectedError(f"{self.wire.name} was disconnected while reconnecting")
        self._reidentify = False
        logger.warning("%s: the hand control answers on a new link: identified", self.wire.name)

    def _needs_reidentifying(self) -> bool:
        return self._reidentify or self._identified_on != self.wire.statistics.reconnects

    def _judge_link(self) -> None:
        """After a failed poll: the link is lost when it is closed, or the device has been
        silent longer than ``stale_after_s`` (a noisy line still answers its resync echoes).
        A lost link reads as not connected and is reopened by the next poll."""
        silent_s = time.monotonic() - self.wire.last_answer_s
        if self.wire.is_open and silent_s <= self.stale_after_s:
            return
        self._reidentify = True
        if self.state.connected:
            logger.warning("%s: link lost (silent for %.1f s)", self.wire.name, silent_s)
            self._publish(dataclasses.replace(self.state, connected=False))

    async def _motor_version(self, axis: Axis) -> tuple[int, int] | None:
        reply = await self.wire.ask(GetDeviceVersion(axis))
        if isinstance(reply, DeviceVersion):
            return reply.major, reply.minor
        return None  # a failed passthrough: that motor controller did not answer
