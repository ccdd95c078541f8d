"""First run: when no site is saved, the page asks for a site and time check and saves the site
to the settings file (``docs/dashboard.md``, "First run").

The web layer does not know where settings live: whoever starts the dashboard passes a
:class:`SiteStore` (``scopelink serve`` passes one for its settings file, see
``scopelink.cli.site_store``). Without one the page never asks.

- ``GET /api/setup``: ``{"needed": bool, "can_save": bool, "where": str | None, "site": {...},
  "mount_utc": iso}`` (``needed``: a store is given and it holds no site yet);
- ``POST /api/setup``: ``{"latitude_deg", "longitude_deg", "elevation_m"?, "utc"?}``: sets the
  mount's site (and its clock, when ``utc`` is given), then saves the site to the store.
  The mount is told first: a site the mount refuses is never saved. Only while ``needed``:
  afterwards (or with no store) it is refused with 409 and changes nothing.
"""

from __future__ import annotations

from typing import Protocol

from aiohttp import web

from scopelink.astro import Site
from scopelink.mount import Mount
from scopelink.web.params import BadRequestError, Body, read_body
from scopelink.web.snapshot import describe_mount
from scopelink.web.timeset import parse_utc

__all__ = ["SiteStore", "SiteStoreError", "add_setup_routes", "site_from_body"]


class SiteStoreError(Exception):
    """The site could not be saved (the message names the file and why)."""


class SiteStore(Protocol):
    """Where the dashboard saves the site chosen at first run."""

    @property
    def saved(self) -> bool:
        """Whether a site is saved already (then the page does not ask)."""
        ...

    @property
    def where(self) -> str:
        """Where it is saved, as the page names it (a file's path)."""
        ...

    def save(self, site: Site) -> None:
        """Save ``site``'s latitude, longitude and elevation (:class:`SiteStoreError`)."""
        ...


def site_from_body(body: Body, current: Site) -> Site:
    """The site a request names (latitude, longitude, optional elevation); the air's pressure,
    temperature and humidity are kept from ``current``."""
    try:
        return Site(
            latitude_deg=body.number("latitude_deg", -90.0, 90.0),
            longitude_deg=body.number("longitude_deg", -180.0, 180.0),
            elevation_m=body.number("elevation_m", -500.0, 10000.0, default=current.elevation_m),
            pressure_hpa=current.pressure_hpa,
            temperature_c=current.temperature_c,
            relative_humidity=current.relative_humidity,
            wavelength_um=current.wavelength_um,
        )
    except ValueError as error:
        raise BadRequestError(str(error)) from None


class _Setup:
    def __init__(self, mount: Mount, store: SiteStore | None) -> None:
        self.mount = mount
        self.store = store

    def _status(self) -> dict[str, object]:
        store = self.store
        site = self.mount.site
        return {
            "needed": store is not None and not store.saved,
            "can_save": store is not None,
            "where": None if store is None else store.where,
            "site": {
                "latitude_deg": site.latitude_deg,
                "longitude_deg": site.longitude_deg,
                "elevation_m": site.elevation_m,
            },
            "mount_utc": self.mount.now().isoformat(),
        }

    async def status(self, request: web.Request) -> web.Response:
        return web.json_response(self._status())

    async def save(self, request: web.Request) -> web.Response:
        body = await read_body(request)
        store = self.store
        if store is None or store.saved:
            # First run only: the settings file is not the web's to rewrite afterwards.
            why = (
                "the site is saved already: change it with 'scopelink config set site.latitude "
                "...' (the Site form changes the mount, not the file)"
                if store is not None
                else "this dashboard has no settings file to save the site to"
            )
            return web.json_response({"error": why, "kind": "SetupDone"}, status=409)
        site = site_from_body(body, self.mount.site)
        utc = parse_utc(body.text("utc", max_length=40)) if body.has("utc") else None
        await self.mount.set_site(site)
        if utc is not None:
            await self.mount.set_time(utc)
        try:
            store.save(site)
        except SiteStoreError as error:
            return web.json_response(
                {"error": f"site set on the mount but not saved: {error}", "kind": "NotSaved"},
                status=500,
            )
        return web.json_response(
            {
                "ok": True,
                "saved_to": store.where,
                "time_set": utc is not None,
                "mount": describe_mount(self.mount),
                "status": self._status(),
            }
        )


def add_setup_routes(app: web.Application, mount: Mount, store: SiteStore | None) -> None:
    setup = _Setup(mount, store)
    app.router.add_get("/api/setup", setup.status)
    app.router.add_post("/api/setup", setup.save)
