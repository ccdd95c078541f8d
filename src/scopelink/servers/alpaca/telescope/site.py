"""The site and the clock: UTCDate, SiteLatitude, SiteLongitude, SiteElevation, DoesRefraction.

Every value is checked at the Mount API too (``docs/reliability-safety.md``, "Setters").
"""

from __future__ import annotations

import re
from dataclasses import replace
from datetime import UTC, datetime

from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope.member import Member, MemberGroup, not_implemented

__all__ = ["SiteMembers", "format_utc", "parse_utc"]

_FRACTION_DIGITS = re.compile(r"(\.\d{6})\d+")


def format_utc(when: datetime) -> str:
    """ASCOM's UTCDate text: ISO 8601 in UTC with a trailing ``Z``."""
    return when.astimezone(UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


def parse_utc(text: str) -> datetime:
    """An ISO 8601 date-time; ``Z`` or an offset, or none (then it is UTC, as ASCOM says)."""
    cleaned = _FRACTION_DIGITS.sub(r"\1", text.strip())  # .NET sends 7 fraction digits
    try:
        when = datetime.fromisoformat(cleaned)
        return when.replace(tzinfo=UTC) if when.tzinfo is None else when.astimezone(UTC)
    except ValueError:
        raise AlpacaError(
            ErrorNumber.INVALID_VALUE,
            f"UTCDate {text!r} is not an ISO 8601 date-time (e.g. 2026-11-22T21:30:00Z)",
        ) from None
    except OverflowError:  # an offset that carries it past year 9999 or before year 1
        raise AlpacaError(
            ErrorNumber.INVALID_VALUE, f"UTCDate {text!r} lies outside any calendar"
        ) from None


class SiteMembers(MemberGroup):
    """The mount's clock and site, read and set."""

    def members(self) -> dict[str, Member]:
        mount = self.session.mount
        return {
            "doesrefraction": Member(
                get=lambda _: mount.site.refracts, put=not_implemented("Setting DoesRefraction")
            ),
            "utcdate": Member(get=lambda _: format_utc(mount.now()), put=self._put_utc_date),
            "sitelatitude": Member(get=lambda _: mount.site.latitude_deg, put=self._put_latitude),
            "sitelongitude": Member(
                get=lambda _: mount.site.longitude_deg, put=self._put_longitude
            ),
            "siteelevation": Member(get=lambda _: mount.site.elevation_m, put=self._put_elevation),
        }

    async def _put_utc_date(self, params: Params) -> None:
        when = parse_utc(params.text("UTCDate"))
        # The Mount API refuses a time no mount can keep (0x401) before a mount that keeps no
        # time says so (0x400): the same value gets the same answer on every mount.
        await self.session.call(self.session.mount.set_time(when))

    async def _set_site(self, **change: float) -> None:
        mount = self.session.mount
        if not mount.capabilities.can_set_site:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount's site cannot be set")
        try:
            site = replace(mount.site, **change)
        except (TypeError, ValueError) as error:
            raise AlpacaError(ErrorNumber.INVALID_VALUE, str(error)) from None
        await self.session.call(mount.set_site(site))

    async def _put_latitude(self, params: Params) -> None:
        await self._set_site(latitude_deg=params.number("SiteLatitude", -90.0, 90.0))

    async def _put_longitude(self, params: Params) -> None:
        await self._set_site(longitude_deg=params.number("SiteLongitude", -180.0, 180.0))

    async def _put_elevation(self, params: Params) -> None:
        await self._set_site(elevation_m=params.number("SiteElevation", -300.0, 10000.0))
