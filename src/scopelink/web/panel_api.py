"""The panel's own endpoints, beside ``api.py``'s commands:

- ``GET /api/object?name=``: what the information panel shows about an object
  (:func:`scopelink.web.objectinfo.object_info`: type, magnitude, size, rise/transit/set, when it
  reaches the mount's horizon or meridian limit), computed off the event loop, one at a time
  (:mod:`scopelink.web.busy`: beyond a few in hand, ``429 Busy``);
- ``POST /api/pushto``: ``{"name": ...}`` makes it the push-to target whose figures ride on every
  WebSocket update (``panel.pushto``); ``{}`` or ``{"name": null}`` stops;
- ``GET``/``POST /api/setup``: the first-run site check (:mod:`scopelink.web.site_check`).
"""

from __future__ import annotations

from aiohttp import web

from scopelink.mount import Mount
from scopelink.web.busy import BusyError, Computations, busy_response
from scopelink.web.live import LiveHub
from scopelink.web.objectinfo import object_info
from scopelink.web.params import BadRequestError, read_body
from scopelink.web.site_check import SiteStore, add_setup_routes

__all__ = ["add_panel_routes"]

_MAX_NAME = 100


class _PanelApi:
    def __init__(self, mount: Mount, hub: LiveHub) -> None:
        self.mount = mount
        self.hub = hub
        self.computations = Computations()

    async def object(self, request: web.Request) -> web.Response:
        name = request.query.get("name", "").strip()
        if not 0 < len(name) <= _MAX_NAME:
            raise BadRequestError(f"'name' must be 1-{_MAX_NAME} characters")
        try:
            info = await self.computations.run(object_info, self.mount, name)
        except BusyError as error:
            return busy_response(error)
        return web.json_response(info)

    async def pushto(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        self.hub.panel.pushto.set(body.text("name") if body.has("name") else None)
        return web.json_response({"ok": True, "target": self.hub.panel.pushto.name})


def add_panel_routes(
    app: web.Application, mount: Mount, hub: LiveHub, site_store: SiteStore | None
) -> None:
    """The panel's routes, and the first-run check's (:mod:`scopelink.web.site_check`)."""
    api = _PanelApi(mount, hub)
    app.router.add_get("/api/object", api.object)
    app.router.add_post("/api/pushto", api.pushto)
    app.on_cleanup.append(api.computations.close)
    add_setup_routes(app, mount, site_store)
