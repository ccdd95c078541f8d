"""The WebSocket side of the dashboard: one broadcaster for every open page.

While at least one page is connected, one task holds ``mount.watching()`` (so the state cache is
polled; each update is a read that raises the poll rate, see docs/mount-api.md), and every
``interval_s`` sends all pages the same update: the mount's state (with what the panel shows
beside it, :class:`~scopelink.web.view_state.PanelView`), the chart's
objects (every ``sky_every`` updates: they cost ERFA time) and the new traffic lines. A page that
cannot take an update within ``send_timeout_s`` is closed rather than allowed to stall the others.
When the last page goes, polling stops.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging

from aiohttp import WSMsgType, web

from scopelink.mount import Mount
from scopelink.mount.deadman import MotionClient
from scopelink.web.almanac import twilight_json
from scopelink.web.sky import SkyPositions, sky_frame, sky_positions
from scopelink.web.snapshot import describe_mount, state_json
from scopelink.web.traffic import TrafficMonitor
from scopelink.web.view_state import PanelView

__all__ = ["LiveHub"]

logger = logging.getLogger(__name__)


class LiveHub:
    """Open pages and the one task that feeds them."""

    def __init__(
        self,
        mount: Mount,
        traffic: TrafficMonitor | None,
        *,
        interval_s: float = 0.25,
        sky_every: int = 2,
        send_timeout_s: float = 5.0,
    ) -> None:
        self._mount = mount
        self._traffic = traffic
        self.interval_s = interval_s
        self._sky_every = max(1, sky_every)
        self._send_timeout_s = send_timeout_s
        self._sockets: set[web.WebSocketResponse] = set()
        self._task: asyncio.Task[None] | None = None
        self._sky: SkyPositions | None = None
        self._traffic_seq = 0
        self._described: dict[str, object] | None = None
        self.panel = PanelView(mount)
        """What the panel shows beside the state (slew progress, health, clock, push-to...)."""

    @property
    def clients(self) -> int:
        return len(self._sockets)

    def sky_json(self) -> dict[str, object]:
        """The chart's objects now, at the mount's site, and the frame that turns its J2000
        data into altitude and azimuth (``sky`` and ``sky_frame`` of a message)."""
        now = self._mount.now()
        site = self._mount.site
        if self._sky is None:
            self._sky = sky_positions(now)
        objects = [obj.as_json() for obj in self._sky.at(now, site)]
        return {"sky": objects, "sky_frame": sky_frame(now, site)}

    def _traffic_json(self, since: int) -> tuple[list[dict[str, object]], int]:
        if self._traffic is None:
            return [], since
        lines = self._traffic.since(since)
        return [line.as_json() for line in lines], (lines[-1].seq if lines else since)

    async def handle(self, request: web.Request) -> web.WebSocketResponse:
        """One page's WebSocket: a hello with everything, then the shared updates."""
        ws = web.WebSocketResponse(heartbeat=20.0, max_msg_size=4096)
        await ws.prepare(request)
        # Dead-man: the pad's moves name this page's session; they stop when the page goes.
        async with self._mount.motion_client(f"dashboard page {request.remote}") as client:
            return await self._serve_page(ws, client)

    async def _serve_page(
        self, ws: web.WebSocketResponse, client: MotionClient
    ) -> web.WebSocketResponse:
        traffic, _ = self._traffic_json(0)
        hello = {
            "type": "hello",
            "panel": await self.panel.as_json(with_clock=True),
            "mount": describe_mount(self._mount),
            "twilight_deg": twilight_json(),
            "traffic_enabled": self._traffic is not None,
            "traffic": traffic,
            "state": state_json(self._mount, self._mount.state),
            "interval_s": self.interval_s,
            "session": client.token,
        }
        hello.update(await asyncio.to_thread(self.sky_json))
        await ws.send_str(json.dumps(hello))
        self._sockets.add(ws)
        self._ensure_running()
        try:
            async for message in ws:
                # Commands go through the JSON API (clear status codes); pages send nothing here.
                if message.type is WSMsgType.ERROR:
                    break
        finally:
            self._sockets.discard(ws)
        return ws

    def _ensure_running(self) -> None:
        if self._task is None or self._task.done():
            self._task = asyncio.create_task(self._run(), name="scopelink dashboard updates")

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        async with self._mount.watching():
            tick = 0
            due = loop.time()
            while self._sockets:
                # A fixed cadence: the time spent building and sending is not added to the period.
                due = max(due + self.interval_s, loop.time())
                await asyncio.sleep(due - loop.time())
                if not self._sockets:
                    break
                tick += 1
                self._mount.poller.demand()  # a page reads continuously: see the poll policy
                try:
                    message = await self.build_update(with_sky=tick % self._sky_every == 0)
                except Exception:  # pages keep their last view; the next tick tries again
                    logger.exception("cannot build the dashboard update")
                    continue
                await self._broadcast(message)

    async def build_update(self, *, with_sky: bool) -> str:
        """One update message as sent to every page (JSON text)."""
        traffic, self._traffic_seq = self._traffic_json(self._traffic_seq)
        update: dict[str, object] = {
            "type": "update",
            "panel": await self.panel.as_json(with_clock=with_sky),
            "state": state_json(self._mount, self._mount.state),
            "traffic": traffic,
        }
        if with_sky:
            # Site and limits can change (another page, the CLI): resend them when they do.
            described = describe_mount(self._mount)
            if described != self._described:
                self._described = described
                update["mount"] = described
            try:
                update.update(await asyncio.to_thread(self.sky_json))
            except Exception:  # a chart without objects beats a dead dashboard
                logger.exception("cannot compute the sky chart's objects")
        return json.dumps(update)

    async def _broadcast(self, message: str) -> None:
        async def send(ws: web.WebSocketResponse) -> None:
            try:
                async with asyncio.timeout(self._send_timeout_s):
                    await ws.send_str(message)
            except (TimeoutError, ConnectionError, RuntimeError):
                self._sockets.discard(ws)
                with contextlib.suppress(Exception):
                    await ws.close()

        await asyncio.gather(*(send(ws) for ws in list(self._sockets)))

    async def close(self) -> None:
        """Close every page and stop the broadcaster (and so the polling it asked for)."""
        for ws in list(self._sockets):
            with contextlib.suppress(Exception):
                await ws.close(code=1001, message=b"dashboard stopping")
        self._sockets.clear()
        task, self._task = self._task, None
        if task is not None:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
