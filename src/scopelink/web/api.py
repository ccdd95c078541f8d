"""The dashboard's JSON API: every command goes through the Mount's public, checked methods.

Errors come back as ``{"error": message, "kind": name}`` with a status that says whose fault it
is: 400 a malformed request, 404 an unknown object (with ``suggestions``), 409 a command the
mount refuses now (below the horizon, parked, not connected), 501 a command this mount lacks,
502 a device that failed to answer.
"""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable

from aiohttp import web

from scopelink.astro.catalog import EphemerisRangeError, UnknownObjectError, lookup, search
from scopelink.mount import (
    DeviceError,
    InvalidValueError,
    LimitError,
    Mount,
    MountAxis,
    MountError,
    NotConnectedError,
    NotSupportedError,
    ParkedError,
    TrackingMode,
)
from scopelink.web.params import BadRequestError, read_body
from scopelink.web.site_check import site_from_body
from scopelink.web.snapshot import describe_mount, state_json
from scopelink.web.timeset import parse_utc
from scopelink.web.track import add_track_routes

__all__ = ["add_api_routes", "error_middleware"]

logger = logging.getLogger(__name__)

Handler = Callable[[web.Request], Awaitable[web.StreamResponse]]

_MAX_SEARCH_RESULTS = 20


def _error(status: int, error: Exception, **extra: object) -> web.Response:
    return web.json_response(
        {"error": str(error), "kind": type(error).__name__, **extra}, status=status
    )


@web.middleware
async def error_middleware(request: web.Request, handler: Handler) -> web.StreamResponse:
    """Turn refusals into JSON errors the page shows; a bug stays a logged 500."""
    try:
        return await handler(request)
    except (BadRequestError, InvalidValueError, EphemerisRangeError) as error:
        return _error(400, error)
    except UnknownObjectError as error:
        return _error(404, error, suggestions=list(error.suggestions))
    except (LimitError, ParkedError, NotConnectedError) as error:
        return _error(409, error)
    except NotSupportedError as error:
        return _error(501, error)
    except (DeviceError, MountError) as error:
        return _error(502, error)


class _Api:
    def __init__(self, mount: Mount) -> None:
        self.mount = mount

    def _ok(self) -> web.Response:
        return web.json_response({"ok": True, "state": state_json(self.mount, self.mount.state)})

    async def state(self, request: web.Request) -> web.Response:
        return web.json_response(
            {
                "mount": describe_mount(self.mount),
                "state": state_json(self.mount, self.mount.state),
            }
        )

    async def search(self, request: web.Request) -> web.Response:
        prefix = request.query.get("q", "")
        if len(prefix) > 100:
            raise BadRequestError("'q' must be at most 100 characters")
        try:
            limit = int(request.query.get("limit", "10"))
        except ValueError:
            raise BadRequestError("'limit' must be a whole number") from None
        if not 1 <= limit <= _MAX_SEARCH_RESULTS:
            raise BadRequestError(f"'limit' must lie in [1, {_MAX_SEARCH_RESULTS}]")
        matches = search(prefix, limit)
        return web.json_response(
            {
                "matches": [
                    {
                        "name": m.name,
                        "matched": m.matched,
                        "kind": m.kind.value,
                        "type": m.type_description,
                        "mag": m.magnitude,
                    }
                    for m in matches
                ]
            }
        )

    async def goto(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        if body.has("name"):
            found = await self.mount.goto_object(body.text("name"))
            return web.json_response(
                {
                    "ok": True,
                    "object": {
                        "name": found.name,
                        "ra_j2000_hours": found.ra_hours,
                        "dec_j2000_deg": found.dec_deg,
                    },
                }
            )
        if body.has("ra_hours") or body.has("dec_deg"):
            await self.mount.goto_equatorial(
                body.number("ra_hours", 0.0, 24.0), body.number("dec_deg", -90.0, 90.0)
            )
            return self._ok()
        if body.has("alt_deg") or body.has("az_deg"):
            await self.mount.goto_horizontal(
                body.number("alt_deg", -90.0, 90.0), body.number("az_deg", 0.0, 360.0) % 360.0
            )
            return self._ok()
        raise BadRequestError("give 'name', or 'ra_hours' and 'dec_deg', or 'alt_deg' and 'az_deg'")

    async def sync(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        if body.has("name"):
            found = lookup(body.text("name"), self.mount.now(), self.mount.site)
            await self.mount.sync_equatorial(found.ra_hours, found.dec_deg)
        else:
            await self.mount.sync_equatorial(
                body.number("ra_hours", 0.0, 24.0), body.number("dec_deg", -90.0, 90.0)
            )
        return self._ok()

    async def pointing(self, request: web.Request) -> web.Response:
        """GET: the PC-side syncs, their residuals and the model (docs/pointing.md)."""
        return web.json_response(self.mount.pointing.summary())

    async def pointing_change(self, request: web.Request) -> web.Response:
        """POST ``{"remove": N}`` (1-based, as listed) or ``{"clear": true}``."""
        body = await read_body(request)
        if body.has("remove"):
            number = body.number("remove", 1.0, 10_000.0)
            if not number.is_integer():
                raise BadRequestError(f"'remove' is a sync's number as listed, not {number:g}")
            self.mount.pointing.remove(int(number))
        elif body.has("clear"):
            self.mount.pointing.clear()
        else:
            raise BadRequestError("give 'remove' (a sync's number) or 'clear'")
        self.mount.pointing_changed()
        return web.json_response(self.mount.pointing.summary())

    async def abort(self, request: web.Request) -> web.Response:
        await read_body(request)
        await self.mount.abort()
        return self._ok()

    async def move(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        axis = body.choice("axis", MountAxis)
        limit = self.mount.capabilities.max_axis_rate_deg_s
        rate = body.number("rate_deg_s", -limit, limit)
        # The page's live session owns the motion: it stops if the page goes (dead-man).
        session = body.text("session") if body.has("session") else None
        with self.mount.acting_for(session) as client:
            if session is not None and client is None and rate != 0.0:
                # Its page's live connection is gone: nothing would stop this motion when the
                # page goes. A stop is always taken.
                return web.json_response(
                    {
                        "error": "this page's live connection is gone: wait for it to come "
                        "back (or reload the page), then press again",
                        "kind": "SessionGone",
                    },
                    status=409,
                )
            await self.mount.move_axis(axis, rate)
        return self._ok()

    async def tracking(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        await self.mount.set_tracking(body.choice("mode", TrackingMode))
        return self._ok()

    async def park(self, request: web.Request) -> web.Response:
        await read_body(request)
        await self.mount.park()
        return self._ok()

    async def unpark(self, request: web.Request) -> web.Response:
        await read_body(request)
        resume = await self.mount.unpark()
        return web.json_response(
            {
                "ok": True,
                "state": state_json(self.mount, self.mount.state),
                "resume": resume.message,
            }
        )

    async def site(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        await self.mount.set_site(site_from_body(body, self.mount.site))
        return web.json_response({"ok": True, "mount": describe_mount(self.mount)})

    async def time(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        await self.mount.set_time(parse_utc(body.text("utc", max_length=40)))
        return self._ok()


def add_api_routes(app: web.Application, mount: Mount) -> None:
    api = _Api(mount)
    app.router.add_get("/api/state", api.state)
    app.router.add_get("/api/search", api.search)
    app.router.add_post("/api/goto", api.goto)
    app.router.add_post("/api/sync", api.sync)
    app.router.add_get("/api/pointing", api.pointing)
    app.router.add_post("/api/pointing", api.pointing_change)
    app.router.add_post("/api/abort", api.abort)
    app.router.add_post("/api/move", api.move)
    app.router.add_post("/api/tracking", api.tracking)
    app.router.add_post("/api/park", api.park)
    app.router.add_post("/api/unpark", api.unpark)
    app.router.add_post("/api/site", api.site)
    app.router.add_post("/api/time", api.time)
    add_track_routes(app, mount)  # GET/POST /api/track: following a moving target
