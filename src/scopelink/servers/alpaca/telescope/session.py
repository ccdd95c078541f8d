"""What every member group shares: the mount, the configuration and the Alpaca client's session.

The session is the client's connection (Connected, Connect), the checks every command makes
(connected, fresh, unparked), the configured equatorial frame, and the moment of the last slew
started here (so that Slewing is true before the state cache has caught up with it).
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable
from datetime import datetime

from scopelink.astro import apparent_to_j2000, j2000_to_apparent, lst_hours
from scopelink.mount import Mount, MountError, MountState, TrackingMode
from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber, from_mount_error
from scopelink.servers.alpaca.telescope.config import EquatorialSystem, TelescopeConfig

__all__ = ["TelescopeSession"]

logger = logging.getLogger(__name__)


class TelescopeSession:
    """The Alpaca client's session with ``mount``: one per served device."""

    def __init__(self, mount: Mount, config: TelescopeConfig) -> None:
        self.mount = mount
        self.config = config
        self.client_connected = False
        """Whether an Alpaca client has connected (the mount may have lost its link since)."""
        self.slew_started_at: datetime | None = None
        """When the last slew or park started here (None once aborted)."""
        self._connect_task: asyncio.Task[None] | None = None

    # --- connection ------------------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        """Whether an Alpaca client has connected and the mount itself is connected."""
        return self.client_connected and self.mount.state.connected

    @property
    def connecting(self) -> bool:
        return self._connect_task is not None and not self._connect_task.done()

    async def connect(self) -> None:
        """Connect the mount if it is not already (other front ends may share it)."""
        if not self.mount.state.connected:
            try:
                await self.mount.connect()
            except MountError as error:
                raise from_mount_error(error) from error
        self.client_connected = True

    def disconnect(self) -> None:
        """Forget the Alpaca connection; the mount stays connected for other front ends."""
        self.client_connected = False

    def start_connect(self) -> None:
        """ITelescopeV4 Connect: connect in the background (Connecting is true meanwhile)."""
        if not self.connecting:
            self._connect_task = asyncio.create_task(self._connect_in_background())

    async def _connect_in_background(self) -> None:
        try:
            await self.connect()
        except AlpacaError as error:
            logger.warning("Alpaca Connect failed: %s", error.message)

    async def close(self) -> None:
        """Stop a Connect still running (the server is shutting down)."""
        task = self._connect_task
        if task is not None and not task.done():
            task.cancel()
            await asyncio.gather(task, return_exceptions=True)

    # --- checks every command makes --------------------------------------------------------------

    def require_connected(self) -> None:
        if not self.client_connected:
            raise AlpacaError(
                ErrorNumber.NOT_CONNECTED, "not connected: set Connected to True (or Connect) first"
            )
        if not self.mount.state.connected:
            self.require_fresh()  # names the link's loss and the last reading's age
            raise AlpacaError(ErrorNumber.NOT_CONNECTED, "the mount has lost its connection")

    def require_fresh(self, *, position: bool = True) -> MountState:
        """The state, if it may be served as current: 0x407 while the link is down, 0x500 when
        the reading is older than the mount's ``stale_after_s`` (both name its age)."""
        try:
            return self.mount.fresh_state(position=position)
        except MountError as error:
            raise from_mount_error(error) from None

    def is_fresh(self, *, position: bool) -> bool:
        try:
            self.mount.fresh_state(position=position)
        except MountError:
            return False
        return True

    def require_unparked(self) -> None:
        if self.mount.state.parked:
            raise AlpacaError(
                ErrorNumber.INVALID_WHILE_PARKED, "the mount is parked: Unpark it first"
            )

    def require_tracking_off(self, what: str) -> None:
        if self.mount.state.tracking is not TrackingMode.OFF:
            raise AlpacaError(
                ErrorNumber.INVALID_OPERATION, f"{what} needs Tracking off (ASCOM): set it False"
            )

    @staticmethod
    async def call(action: Awaitable[None]) -> None:
        """Await a Mount command, its refusal answered as the matching ASCOM error."""
        try:
            await action
        except MountError as error:
            raise from_mount_error(error) from error

    # --- state -----------------------------------------------------------------------------------

    @property
    def slewing(self) -> bool:
        """The cache's word, or True while the cache still predates a slew we just started."""
        state = self.mount.state
        started = self.slew_started_at
        return state.slewing or (started is not None and state.read_at < started)

    @staticmethod
    def known(value: float | None, what: str) -> float:
        """``value``, or 0x500 while the mount has not reported it yet."""
        if value is None:
            raise AlpacaError(
                ErrorNumber.DRIVER_ERROR, f"the mount has not reported its {what} yet"
            )
        return value

    def sidereal_time(self) -> float:
        """Local apparent sidereal time (hours) at the mount's clock and site."""
        return lst_hours(self.mount.now(), self.mount.site.longitude_deg)

    # --- the configured equatorial frame ---------------------------------------------------------

    def radec_if_known(self, state: MountState) -> tuple[float | None, float | None]:
        """RA/Dec of ``state`` in the configured frame (None before the first reading)."""
        if self.config.equatorial_system is EquatorialSystem.J2000:
            return state.ra_j2000_hours, state.dec_j2000_deg
        return state.ra_of_date_hours, state.dec_of_date_deg

    def radec(self) -> tuple[float, float]:
        """The current RA/Dec in the configured frame."""
        ra, dec = self.radec_if_known(self.mount.state)
        return self.known(ra, "position"), self.known(dec, "position")

    def to_j2000(self, ra_hours: float, dec_deg: float) -> tuple[float, float]:
        """Client coordinates (the configured frame) as J2000."""
        if self.config.equatorial_system is EquatorialSystem.J2000:
            return ra_hours, dec_deg
        return apparent_to_j2000(ra_hours, dec_deg, self.mount.now())

    def to_apparent(self, ra_hours: float, dec_deg: float) -> tuple[float, float]:
        """Client coordinates (the configured frame) as the apparent place of date."""
        if self.config.equatorial_system is EquatorialSystem.TOPOCENTRIC:
            return ra_hours, dec_deg
        return j2000_to_apparent(ra_hours, dec_deg, self.mount.now())
