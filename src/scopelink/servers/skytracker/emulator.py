"""Ready-made emulators over a :class:`~scopelink.sim.SimulatedMount` (alt-az preset).

* :class:`SkyTrackerEmulator`: the Sky Tracker box with the Sky Commander behind its bus, joined
  by a real link pair; the PC talks to the Sky Tracker's port.
* :class:`SkyCommanderEmulator`: the Sky Commander alone on its own port (what INDI's Sky
  Commander driver connects to), reading the mount's axes as encoders.

Both are :class:`~scopelink.servers.hosting.HostedDevice` s (async context managers): serve a
pty, TCP port or memory pair with ``on_pty()`` / ``on_tcp()`` / ``on_memory()``, or a link of
your own with ``serve(link)``. They pace their replies themselves (and read a pty's line
settings), so they host links unwrapped.
"""

from __future__ import annotations

import asyncio
import contextlib
from pathlib import Path
from types import TracebackType
from typing import Self

from scopelink.links import Link, memory_pair
from scopelink.mount import AlignmentMode
from scopelink.servers.faults import FaultInjector
from scopelink.servers.hosting import HostedDevice
from scopelink.sim import SimulatedMount

from .commander import SkyCommander
from .line import DEFAULT_JITTER_ALLOWANCE_S
from .objects import ObjectStore
from .port import DevicePort
from .tracker import SkyTracker


def require_alt_az(mount: SimulatedMount, device: str) -> None:
    """Refuse a mount these devices cannot sit on: the Sky Tracker drives, and the Sky Commander
    reads, the two axes of an alt-azimuth telescope (the spec's first line)."""
    if mount.model.alignment_mode is not AlignmentMode.ALT_AZ:
        mode = mount.model.alignment_mode.name.lower().replace("_", " ")
        raise ValueError(
            f"the {device} works on an alt-azimuth telescope only, not the {mount.model.name} "
            f"({mode}): use an alt-az preset such as SKY_TRACKER"
        )


def commander_for(mount: SimulatedMount, data_dir: Path) -> SkyCommander:
    """A Sky Commander whose encoders are ``mount``'s axes (counters are altitude, azimuth)."""

    def encoders() -> tuple[float, float]:
        return mount.observed_at(mount.clock.elapsed())

    return SkyCommander(encoders, mount.clock.now, mount.site, ObjectStore(data_dir))


class SkyCommanderEmulator(HostedDevice):
    """The Sky Commander alone on its serial port (9600 baud replies, faults, pty framing)."""

    def __init__(
        self,
        mount: SimulatedMount,
        data_dir: Path,
        *,
        faults: FaultInjector | None = None,
        pace: bool = True,
    ) -> None:
        require_alt_az(mount, "Sky Commander")
        super().__init__(self.serve)
        self.commander = commander_for(mount, data_dir)
        self.faults = faults if faults is not None else FaultInjector()
        self._pace = pace

    async def serve(self, link: Link) -> None:
        """Serve one client on ``link`` until it closes."""
        await self.commander.serve(DevicePort(link, faults=self.faults, pace=self._pace))


class SkyTrackerEmulator(HostedDevice):
    """The Sky Tracker box driving ``mount``'s axes, its Sky Commander on a real link pair.

    ``strict_line`` makes the PC port lose characters that come faster than 8N2 (see
    ``line.py``); ``faults`` apply to the Sky Tracker's own replies, ``commander_faults`` to the
    Sky Commander's replies on the bus (those the box relays to the PC and its own polls).
    """

    def __init__(
        self,
        mount: SimulatedMount,
        data_dir: Path,
        *,
        faults: FaultInjector | None = None,
        pace: bool = True,
        strict_line: bool = False,
        jitter_allowance_s: float = DEFAULT_JITTER_ALLOWANCE_S,
        commander_faults: FaultInjector | None = None,
    ) -> None:
        require_alt_az(mount, "Sky Tracker")
        super().__init__(self.serve)
        self.mount = mount
        self.faults = faults if faults is not None else FaultInjector()
        self.commander_faults = (
            commander_faults if commander_faults is not None else FaultInjector()
        )
        self.commander = commander_for(mount, data_dir)
        self._tracker_end, self._commander_end = memory_pair(
            ("sky tracker -> sky commander", "sky commander <- sky tracker")
        )
        azimuth, altitude = mount.axes
        self.tracker = SkyTracker(
            altitude=altitude,
            azimuth=azimuth,
            clock=mount.clock,
            bus=self._tracker_end,
            data_dir=data_dir,
        )
        self._pace = pace
        self._strict_line = strict_line
        self._jitter_allowance_s = jitter_allowance_s
        self._commander_task: asyncio.Task[None] | None = None

    def port_for(self, link: Link) -> DevicePort:
        """The Sky Tracker's PC port on ``link``, with this emulator's line options."""
        return DevicePort(
            link,
            faults=self.faults,
            pace=self._pace,
            strict=self._strict_line,
            jitter_allowance_s=self._jitter_allowance_s,
        )

    async def serve(self, link: Link) -> None:
        """Serve one PC on ``link`` until it closes."""
        await self.tracker.serve(self.port_for(link))

    async def __aenter__(self) -> Self:
        self._commander_task = asyncio.create_task(
            self.commander.serve(
                DevicePort(self._commander_end, faults=self.commander_faults, pace=self._pace)
            ),
            name="sky commander on the bus",
        )
        await self.tracker.__aenter__()
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        await self.close()
        await self.tracker.__aexit__(exc_type, exc, traceback)
        if self._commander_task is not None:
            self._commander_task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._commander_task
        await self._tracker_end.close()
        await self._commander_end.close()
