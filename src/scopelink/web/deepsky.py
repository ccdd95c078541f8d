"""The deep-sky objects the sky chart draws, served once per page load as a compact list.

``GET /api/sky/deepsky`` answers ``{"fields": [...], "objects": [[...], ...]}`` from the
catalogue the package ships (OpenNGC via ``pyongc``, :mod:`scopelink.astro.catalog.deepsky`):
every cluster, nebula and galaxy of magnitude ``CHART_DEEP_SKY_MAGNITUDE`` or brighter, and
every Messier, Caldwell or commonly named one whatever its magnitude, with its J2000 position
and size. Positions do not change over a night (no proper motion worth a pixel), so the list is
built once per process, off the event loop, and kept as gzip-ready bytes; the browser may keep
it for a day. The chart converts positions to the sky of the moment itself (docs/dashboard.md,
"Sky chart").
"""

from __future__ import annotations

import asyncio
import json
from functools import cache

from aiohttp import web

from scopelink.astro.catalog.deepsky import load_deep_sky, load_deep_sky_shapes
from scopelink.astro.catalog.entries import CatalogEntry, FixedPosition, Prominence

__all__ = [
    "CHART_DEEP_SKY_CACHE_S",
    "CHART_DEEP_SKY_MAGNITUDE",
    "add_deep_sky_route",
    "deep_sky_json",
]

CHART_DEEP_SKY_MAGNITUDE = 13.0
"""The faintest deep-sky object the chart draws unless it is named (Messier, Caldwell, common)."""

CHART_DEEP_SKY_CACHE_S = 86400
"""How long a browser may keep the list (``Cache-Control: max-age``)."""

_FIELDS = ["name", "type", "ra_deg", "dec_deg", "mag", "major_arcmin", "minor_arcmin", "pa_deg"]

# OpenNGC's type descriptions -> the chart's symbols; types not listed (stars, double stars,
# novae, unknown objects) are not drawn as deep-sky objects.
_SYMBOLS = {
    "Galaxy": "galaxy",
    "Galaxy Pair": "galaxy",
    "Galaxy Triplet": "galaxy",
    "Group of galaxies": "galaxy",
    "Open Cluster": "open",
    "Association of stars": "open",
    "Globular Cluster": "globular",
    "Planetary Nebula": "planetary",
    "Nebula": "nebula",
    "HII Ionized region": "nebula",
    "Emission Nebula": "nebula",
    "Reflection Nebula": "nebula",
    "Dark Nebula": "nebula",
    "Supernova remnant": "nebula",
    "Star cluster + Nebula": "cluster-nebula",
}


def _drawn(entry: CatalogEntry) -> bool:
    if entry.type_description not in _SYMBOLS:
        return False
    if entry.prominence <= Prominence.CALDWELL:
        return True
    return entry.magnitude is not None and entry.magnitude <= CHART_DEEP_SKY_MAGNITUDE


def _round(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)


@cache
def deep_sky_json() -> bytes:
    """The whole answer, built at the first call (about 0.3 s) and kept."""
    shapes = load_deep_sky_shapes()
    objects: list[list[object]] = []
    for entry in load_deep_sky():
        position = entry.position
        if not _drawn(entry) or not isinstance(position, FixedPosition):
            continue
        major, minor, angle = next(
            (shapes[n] for n in (entry.name, *entry.aliases) if n in shapes), (None, None, None)
        )
        objects.append(
            [
                entry.name,
                _SYMBOLS[entry.type_description],
                round(position.ra_hours * 15.0, 4),
                round(position.dec_deg, 4),
                _round(entry.magnitude, 1),
                _round(major, 1),
                _round(minor, 1),
                _round(angle, 0),
            ]
        )
    # Brightest first: the chart labels in this order and may stop early when zoomed out.
    objects.sort(key=lambda row: 99.0 if row[4] is None else float(str(row[4])))
    return json.dumps({"fields": _FIELDS, "objects": objects}, separators=(",", ":")).encode()


async def _deep_sky(request: web.Request) -> web.Response:
    body = await asyncio.to_thread(deep_sky_json)
    response = web.Response(
        body=body,
        content_type="application/json",
        headers={"Cache-Control": f"max-age={CHART_DEEP_SKY_CACHE_S}"},
    )
    response.enable_compression()
    return response


def add_deep_sky_route(app: web.Application) -> None:
    """Register ``GET /api/sky/deepsky`` on the dashboard's application."""
    app.router.add_get("/api/sky/deepsky", _deep_sky)
