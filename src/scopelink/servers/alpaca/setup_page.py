"""The read-only HTML setup pages (``/setup`` and ``/setup/v1/telescope/0/setup``).

Alpaca clients open these in a browser. They show what the server serves and where; every
value is escaped, since names and limits come from configuration a user typed; control
characters and unencodable surrogates are shown as U+FFFD (docs/reliability-injection.md).
"""

from __future__ import annotations

import re
from html import escape

from scopelink.mount import Mount
from scopelink.servers.alpaca.telescope import TelescopeConfig

__all__ = ["render_setup_page"]


_UNSHOWABLE = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f\ud800-\udfff]")
"""Control characters (NUL...) and lone surrogates (a name from argv bytes that were not UTF-8,
which cannot be encoded): shown as U+FFFD rather than sent raw or failing the page."""


def _text(value: object) -> str:
    return escape(_UNSHOWABLE.sub("\ufffd", str(value)))


def _row(name: str, value: object) -> str:
    return f"<tr><th>{_text(name)}</th><td>{_text(value)}</td></tr>"


def render_setup_page(
    mount: Mount, config: TelescopeConfig, *, unique_id: str, port: int, discovery_port: int | None
) -> str:
    """One HTML page describing the telescope, its site, its limits and the server."""
    site = mount.site
    limits = mount.limits
    identity = mount.identity
    profile = ", ".join(f"{az:g}°: {alt:g}°" for az, alt in limits.horizon_profile) or "none"
    rows = [
        _row("Device", f"telescope/0: {config.name}"),
        _row("Mount", f"{identity.protocol} {identity.model} {identity.firmware}".strip()),
        _row("Link", identity.link or "-"),
        _row("UniqueID", unique_id),
        _row("Equatorial system", config.equatorial_system.name),
        _row("Site latitude", f"{site.latitude_deg:.6f}°"),
        _row("Site longitude", f"{site.longitude_deg:.6f}° (east positive)"),
        _row("Site elevation", f"{site.elevation_m:g} m"),
        _row("Horizon", f"{limits.horizon_deg:g}°"),
        _row("Horizon profile (azimuth: altitude)", profile),
        _row("Maximum altitude", f"{limits.max_altitude_deg:g}°"),
        _row("Alpaca port", port),
        _row("Discovery port", discovery_port if discovery_port is not None else "off"),
    ]
    title = _text(f"scopelink Alpaca telescope: {config.name}")
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{title}</title></head><body><h1>{title}</h1>"
        "<p>Settings are read-only here: set site and limits on the scopelink command line.</p>"
        f"<table>{''.join(rows)}</table></body></html>\n"
    )
