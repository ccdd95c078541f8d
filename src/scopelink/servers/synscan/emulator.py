"""A SynScan hand control on a link: the server, its hand-control state and where it is served.

In front of a :class:`~scopelink.sim.SimulatedMount` it is the emulator; in front of any other
connected :class:`~scopelink.mount.Mount` it is a bridge. Use it as an async context manager::

    async with SynScanEmulator(mount) as emulator:
        path = await emulator.on_pty()        # or on_tcp(), or on_memory() for tests
        ...
"""

from __future__ import annotations

from types import TracebackType
from typing import Self

from scopelink.mount import Mount
from scopelink.servers.access import AccessControl, AccessPolicy
from scopelink.servers.faults import FaultInjector
from scopelink.servers.hosting import SERIAL_9600_8N1, HostedDevice, WireSpeed
from scopelink.servers.synscan.config import SynScanConfig
from scopelink.servers.synscan.device import SynScanHandControl
from scopelink.servers.synscan.server import SynScanServer

__all__ = ["SynScanEmulator"]


class SynScanEmulator(HostedDevice):
    """A SynScan hand control in front of ``mount`` (connected on entry if it is not yet).

    ``wire`` paces replies at a serial line's speed (9600 8N1 by default; None sends at once).
    ``faults`` is the injector tests and the command line drive. ``access`` limits who connects
    over TCP and how fast, and makes it read-only; ``dead_man`` stops a rate slew a client
    started when its link goes (a bridge for phone apps; a hand control on a cable cannot notice);
    ``axis_passthrough=False`` (a bridge) answers the motor passthrough "slow goto" and "set axis
    position" as over a real device, since they would move an axis past every limit check.
    ``cold_start`` starts it as just switched on with the tube where ``mount`` points: the
    counters at their power-on values, not aligned (see :meth:`power_cycle`).
    """

    def __init__(
        self,
        mount: Mount,
        config: SynScanConfig | None = None,
        *,
        faults: FaultInjector | None = None,
        wire: WireSpeed | None = SERIAL_9600_8N1,
        access: AccessPolicy | None = None,
        dead_man: bool = False,
        axis_passthrough: bool = True,
        cold_start: bool = False,
    ) -> None:
        self.cold_start = cold_start
        self._switched_on_mount = False
        control = AccessControl(access, "SynScan")
        self.hand_control = SynScanHandControl(mount, config, axis_passthrough=axis_passthrough)
        self.server = SynScanServer(self.hand_control, faults, access=control, dead_man=dead_man)
        super().__init__(self.server.serve, wire=wire, access=control)

    @property
    def mount(self) -> Mount:
        return self.hand_control.mount

    @property
    def faults(self) -> FaultInjector:
        return self.server.faults

    async def __aenter__(self) -> Self:
        self._switched_on_mount = not self.mount.state.connected
        if self._switched_on_mount:
            await self.mount.connect()
        if self.cold_start:
            await self.hand_control.power_cycle()
        else:
            await self.hand_control.power_on()
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        """Stop serving, then switch off the mount if entering switched it on (its watchers end)."""
        await super().__aexit__(exc_type, exc, traceback)
        if self._switched_on_mount:
            self._switched_on_mount = False
            await self.mount.disconnect()

    async def power_cycle(self) -> None:
        """Switch the emulated hand control off and on: see ``SynScanHandControl.power_cycle``."""
        await self.hand_control.power_cycle()
