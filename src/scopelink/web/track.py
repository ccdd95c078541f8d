"""The dashboard's data for following a moving target (issue #16; the page is drawn elsewhere).

- ``GET /api/track``: ``{"target": name|null, "kind": "sun|moon|planet|comet|asteroid|satellite"|
  null, "error_arcsec": float|null, "path": [[ra_j2000_deg, dec_j2000_deg], ...], "phase":
  "slewing|waiting|following"|null, "ended": reason|null}``. ``path`` is the target's next 60
  minutes in 60 points (a satellite: the stretch of its pass being followed); ``error_arcsec``
  the last tracking error measured (null while slewing). After following ends, ``target`` is
  null and ``ended`` says why.
- ``POST /api/track {"target": "moon"}`` starts following a Sun/Moon/planet by name (the same
  checks as ``scopelink track``: refused before anything moves with 409 for the Sun while Sun
  avoidance is on, 501 on a mount without custom rates, 400 for an unknown name);
  ``{"target": null}`` stops it (rates back to zero). Comets and satellites need a file on the
  server: only ``scopelink track`` follows them (the page cannot name server files).

POSTs pass the dashboard's access policy like every other command (allow-list, read-only,
pairing, request rate: ``web/dashboard.py``). Following is the server's, not a page's: it goes on
when the page closes, as tracking does, until stopped here, from the command line, or by the end
of the target's visibility.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from datetime import datetime

from aiohttp import web

from scopelink.astro.targets import MovingTarget, TargetError, solar_system_target
from scopelink.mount import Mount, MountError
from scopelink.mount.follow import TargetFollower
from scopelink.web.params import BadRequestError, read_body

__all__ = ["PATH_MINUTES", "PATH_POINTS", "TrackService", "add_track_routes"]

logger = logging.getLogger(__name__)

PATH_MINUTES = 60.0
PATH_POINTS = 60
_PATH_REFRESH_S = 30.0
"""The path is computed again after this many seconds of the mount's clock."""


class TrackService:
    """At most one follower per dashboard, run as a task of the server."""

    def __init__(self, mount: Mount) -> None:
        self.mount = mount
        self.follower: TargetFollower | None = None
        self._task: asyncio.Task[None] | None = None
        self._stop = asyncio.Event()
        self._ended: str | None = None
        self._path: tuple[datetime, list[list[float]]] | None = None

    def _target(self, name: str) -> MovingTarget:
        try:
            return solar_system_target(name, self.mount.site)
        except TargetError as error:
            raise BadRequestError(str(error)) from None

    async def start(self, name: str) -> None:
        follower = TargetFollower(self.mount, self._target(name))
        try:
            follower.check()  # refusals (Sun, no custom rates, limits) before anything moves
        except TargetError as error:
            raise BadRequestError(str(error)) from None
        await self.stop()
        self.follower, self._ended, self._path = follower, None, None
        self._stop = asyncio.Event()
        self._task = asyncio.create_task(self._run(follower, self._stop), name="web track")

    async def _run(self, follower: TargetFollower, stop: asyncio.Event) -> None:
        try:
            result = await follower.run(stop=stop)
            reason = result.reason
        except MountError as error:
            reason = str(error)
            logger.warning("following %s ended: %s", follower.target.name, error)
        if self.follower is follower:
            self.follower, self._ended = None, reason

    async def stop(self) -> None:
        task, self._task = self._task, None
        if task is not None and not task.done():
            self._stop.set()
            try:
                await asyncio.wait_for(asyncio.shield(task), 10.0)
            except TimeoutError:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
        if self.follower is not None:
            self.follower, self._ended = None, "stopped"

    def _path_now(self, follower: TargetFollower) -> list[list[float]]:
        now = self.mount.now()
        if self._path is not None and abs((now - self._path[0]).total_seconds()) < _PATH_REFRESH_S:
            return self._path[1]
        plan = follower.result.plan
        if plan is None:
            points = follower.target.path(now, PATH_MINUTES, PATH_POINTS)
        else:  # a satellite: the stretch of its pass being followed
            minutes = (plan.end - plan.start).total_seconds() / 60.0
            points = follower.target.path(plan.start, minutes, PATH_POINTS)
        path = [[ra, dec] for ra, dec in points]
        self._path = (now, path)
        return path

    def as_json(self) -> dict[str, object]:
        follower = self.follower
        if follower is None:
            return {
                "target": None,
                "kind": None,
                "error_arcsec": None,
                "path": [],
                "phase": None,
                "ended": self._ended,
            }
        last = follower.last
        return {
            "target": follower.target.name,
            "kind": follower.target.kind.value,
            "error_arcsec": None if last is None else last.error_arcsec,
            "path": self._path_now(follower),
            "phase": None if last is None else last.phase,
            "ended": None,
        }


def add_track_routes(app: web.Application, mount: Mount) -> None:
    service = TrackService(mount)

    async def get(request: web.Request) -> web.Response:
        return web.json_response(service.as_json())

    async def post(request: web.Request) -> web.Response:
        body = await read_body(request)
        if body.has("target"):
            await service.start(body.text("target", max_length=40))
        else:
            await service.stop()
        return web.json_response({"ok": True, **service.as_json()})

    async def cleanup(app: web.Application) -> None:
        await service.stop()

    app.router.add_get("/api/track", get)
    app.router.add_post("/api/track", post)
    app.on_cleanup.append(cleanup)
