"""The dashboard's "Sky Commander memory" and push-to API (issue #15 part 4), beside ``api.py``.

- ``GET /api/skycommander/slots``: ``{"available": bool, "slots": [...]}``, what scopelink last
  wrote (the mirror of ``scopelink skycommander slots``); ``available`` is false for a mount
  without a Sky Commander (the panel then hides its controls).
- ``POST /api/skycommander/upload``: ``{"name": ...}`` or ``{"ra_hours", "dec_deg", "label"}``,
  optional ``"slot"`` (default: the first slot scopelink has not written);
- ``POST /api/skycommander/clear``: ``{"slot": n}`` or ``{}`` for every slot scopelink wrote:
  the pole is written over them, as ``scopelink skycommander clear`` does;
- ``GET /api/pushto?name=...`` (or ``ra_hours`` and ``dec_deg``): the push-to figures from the
  mount's last reading, for any mount (the same figures as ``scopelink skycommander pushto``).

Errors are the API's (``api.py``): 400 bad input, 404 unknown name, 409 refused (Sun, no
position yet), 501 no Sky Commander, 502 the device failed.
"""

from __future__ import annotations

from aiohttp import web

from scopelink.astro.catalog import lookup
from scopelink.drivers.skytracker.memory import (
    SLOT_COUNT,
    ObjectStorer,
    SlotMirror,
    check_away_from_sun,
    mirror_key,
    placeholder,
    upload,
)
from scopelink.drivers.skytracker.plan import PlanError, PlanItem, entries_for
from scopelink.drivers.skytracker.pushto import push_to
from scopelink.mount import InvalidValueError, Mount, NotSupportedError
from scopelink.mount.memory import RecordError
from scopelink.web.api import Handler
from scopelink.web.params import BadRequestError, Body, read_body

__all__ = ["add_skycommander_routes"]


class _SkyCommanderApi:
    def __init__(self, mount: Mount) -> None:
        self.mount = mount

    def _storer(self) -> tuple[ObjectStorer, SlotMirror]:
        mount = self.mount
        spec = getattr(mount, "spec", None)
        if not isinstance(mount, ObjectStorer) or not isinstance(spec, str):
            raise NotSupportedError("this mount has no Sky Commander memory")
        return mount, SlotMirror(mirror_key(spec))

    def _slots(self, mirror: SlotMirror) -> list[dict[str, object]]:
        return [entry.as_json() for _, entry in sorted(mirror.entries().items())]

    async def slots(self, request: web.Request) -> web.Response:
        try:
            _, mirror = self._storer()
        except NotSupportedError:
            return web.json_response({"available": False, "slots": []})
        return web.json_response({"available": True, "slots": self._slots(mirror)})

    def _slot(self, body: Body) -> int | None:
        if not body.has("slot"):
            return None
        slot = body.number("slot", 0, SLOT_COUNT - 1)
        if slot != int(slot):
            raise BadRequestError(f"'slot' must be a whole number 0-{SLOT_COUNT - 1}")
        return int(slot)

    async def upload(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        storer, mirror = self._storer()
        slot = self._slot(body)
        if slot is None:
            taken = mirror.entries()
            slot = next((n for n in range(SLOT_COUNT) if n not in taken), None)
            if slot is None:
                raise InvalidValueError("every slot holds an object scopelink wrote: clear one")
        now, site = self.mount.now(), self.mount.site
        if body.has("name"):
            found = lookup(body.text("name"), now, site)  # 404 with suggestions
            ra, dec, label = found.ra_hours, found.dec_deg, found.name
        elif body.has("ra_hours") or body.has("dec_deg"):
            ra = body.number("ra_hours", 0.0, 24.0) % 24.0
            dec = body.number("dec_deg", -90.0, 90.0)
            label = body.text("label") if body.has("label") else f"RA {ra:.3f} Dec {dec:+.3f}"
        else:
            raise BadRequestError("give 'name', or 'ra_hours' and 'dec_deg'")
        radius = self.mount.limits.sun_avoidance_deg
        check_away_from_sun(label, ra, dec, now, radius)  # 409
        item = PlanItem("the request", slot, None, ra, dec, label)
        try:
            entries = entries_for([item], start=slot, when=now, site=site, sun_avoidance_deg=radius)
        except PlanError as error:
            raise BadRequestError(str(error)) from None
        written = await upload(storer, mirror, entries, self.mount.now())
        return web.json_response(
            {"ok": True, "written": [e.as_json() for e in written], "slots": self._slots(mirror)}
        )

    async def clear(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        storer, mirror = self._storer()
        slot = self._slot(body)
        slots = [slot] if slot is not None else sorted(mirror.entries())
        ra, dec = placeholder(self.mount.site)
        for each in slots:
            await storer.store_object(each, ra, dec)
            mirror.forget([each])
        return web.json_response({"ok": True, "cleared": slots, "slots": self._slots(mirror)})

    async def pushto(self, request: web.Request) -> web.Response:
        query = request.query
        state = self.mount.state
        when = state.read_at
        if "name" in query:
            name = query["name"]
            if not 0 < len(name) <= 100:
                raise BadRequestError("'name' must be 1-100 characters")
            found = lookup(name, when, self.mount.site)
            ra, dec, label = found.ra_hours, found.dec_deg, found.name
        else:
            try:
                body = Body({k: float(query[k]) for k in ("ra_hours", "dec_deg") if k in query})
            except ValueError:
                raise BadRequestError("'ra_hours' and 'dec_deg' must be numbers") from None
            ra = body.number("ra_hours", 0.0, 24.0)
            dec = body.number("dec_deg", -90.0, 90.0)
            label = f"RA {ra:.3f} Dec {dec:+.3f}"
        figures = push_to(label, ra % 24.0, dec, state=state, when=when, site=self.mount.site)
        return web.json_response(figures.as_json())


def _mirror_errors(handler: Handler) -> Handler:
    """A damaged mirror file is a 409 naming the file (never a bare 500)."""

    async def guarded(request: web.Request) -> web.StreamResponse:
        try:
            return await handler(request)
        except RecordError as error:
            return web.json_response({"error": str(error), "kind": "RecordError"}, status=409)

    return guarded


def add_skycommander_routes(app: web.Application, mount: Mount) -> None:
    api = _SkyCommanderApi(mount)
    app.router.add_get("/api/skycommander/slots", _mirror_errors(api.slots))
    app.router.add_post("/api/skycommander/upload", _mirror_errors(api.upload))
    app.router.add_post("/api/skycommander/clear", _mirror_errors(api.clear))
    app.router.add_get("/api/pushto", api.pushto)
