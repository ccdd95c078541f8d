"""The read-only HTML setup pages (``/setup`` and ``/setup/v1/telescope/0/setup``).

Alpaca clients open these in a browser. They show what the server serves and where; every
value is escaped, since names and limits come from configuration a user typed.
"""

from __future__ import annotations

from html import escape

from scopelink.mount import Mount
from scopelink.servers.alpaca.telescope import TelescopeConfig

__all__ = ["render_setup_page"]


def _row(name: str, value: object) -> str:
    return f"<tr><th>{escape(name)}</th><td>{escape(str(value))}</td></tr>"


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
    title = escape(f"scopelink Alpaca telescope: {config.name}")
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{title}</title></head><body><h1>{title}</h1>"
        "<p>Settings are read-only here: set site and limits on the scopelink command line.</p>"
        f"<table>{''.join(rows)}</table></body></html>\n"
    )
