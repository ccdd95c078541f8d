"""Ready-made emulators over a :class:`~scopelink.sim.SimulatedMount` (alt-az preset).

* :class:`SkyTrackerEmulator`: the Sky Tracker box with the Sky Commander behind its bus, joined
  by a real link pair; the PC talks to the Sky Tracker's port.
* :class:`SkyCommanderEmulator`: the Sky Commander alone on its own port (what INDI's Sky
  Commander driver connects to), reading the mount's axes as encoders.

Both are async context managers; serve a link with ``serve(link)``, or a pty / TCP port with
``open_pty()`` / ``listen_tcp()``.
"""

from __future__ import annotations

import asyncio
import contextlib
from pathlib import Path
from types import TracebackType
from typing import Self

from scopelink.links import Link, PtyLink, TcpServer, memory_pair, open_pty, serve_tcp
from scopelink.servers.faults import FaultInjector
from scopelink.sim import SimulatedMount

from .commander import SkyCommander
from .line import DEFAULT_JITTER_ALLOWANCE_S
from .objects import ObjectStore
from .port import DevicePort
from .tracker import SkyTracker


def commander_for(mount: SimulatedMount, data_dir: Path) -> SkyCommander:
    """A Sky Commander whose encoders are ``mount``'s axes (counters are altitude, azimuth)."""

    def encoders() -> tuple[float, float]:
        return mount.observed_at(mount.clock.elapsed())

    return SkyCommander(encoders, mount.clock.now, mount.site, ObjectStore(data_dir))


class _Emulator:
    """Serving machinery shared by both emulators: background ports, pty, TCP."""

    def __init__(self) -> None:
        self._background: set[asyncio.Task[None]] = set()
        self._links: list[Link] = []
        self._servers: list[TcpServer] = []

    async def serve(self, link: Link) -> None:
        """Serve one client on ``link`` until it closes."""
        raise NotImplementedError

    def serve_in_background(self, link: Link) -> asyncio.Task[None]:
        """Serve ``link`` in a task that ends with the emulator (the link is closed then)."""
        self._links.append(link)
        task = asyncio.create_task(self.serve(link), name=f"serve {link.name}")
        self._background.add(task)
        task.add_done_callback(self._background.discard)
        return task

    async def open_pty(self, symlink: str | Path | None = None) -> PtyLink:
        """A pseudo-terminal served in the background; clients open ``.path``."""
        link = await open_pty(symlink)
        self.serve_in_background(link)
        return link

    async def listen_tcp(self, host: str = "127.0.0.1", port: int = 0) -> TcpServer:
        """Serve TCP connections on ``host:port`` (port 0 picks one: read ``.port``)."""
        server = await serve_tcp(self.serve, host=host, port=port)
        self._servers.append(server)
        return server

    async def _stop_serving(self) -> None:
        for server in self._servers:
            await server.close()
        for task in list(self._background):
            task.cancel()
        await asyncio.gather(*self._background, return_exceptions=True)
        for link in self._links:
            await link.close()


class SkyCommanderEmulator(_Emulator):
    """The Sky Commander alone on its serial port (9600 baud replies, faults, pty framing)."""

    def __init__(
        self,
        mount: SimulatedMount,
        data_dir: Path,
        *,
        faults: FaultInjector | None = None,
        pace: bool = True,
    ) -> None:
        super().__init__()
        self.commander = commander_for(mount, data_dir)
        self.faults = faults if faults is not None else FaultInjector()
        self._pace = pace

    async def serve(self, link: Link) -> None:
        await self.commander.serve(DevicePort(link, faults=self.faults, pace=self._pace))

    async def __aenter__(self) -> Self:
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        await self._stop_serving()


class SkyTrackerEmulator(_Emulator):
    """The Sky Tracker box driving ``mount``'s axes, its Sky Commander on a real link pair.

    ``strict_line`` makes the PC port lose characters that come faster than 8N2 (see
    ``line.py``); ``faults`` apply to the Sky Tracker's own replies.
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
    ) -> None:
        super().__init__()
        self.mount = mount
        self.faults = faults if faults is not None else FaultInjector()
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
        await self.tracker.serve(self.port_for(link))

    async def __aenter__(self) -> Self:
        self._commander_task = asyncio.create_task(
            self.commander.serve(DevicePort(self._commander_end, pace=self._pace)),
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
        await self._stop_serving()
        await self.tracker.__aexit__(exc_type, exc, traceback)
        if self._commander_task is not None:
            self._commander_task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._commander_task
        await self._tracker_end.close()
        await self._commander_end.close()
