"""Where the dashboard's first-run check saves the site: the settings file's ``[site]`` table
(``scopelink.web.site_check``, ``docs/dashboard.md``, "First run").

The file is edited as ``scopelink config set`` edits it (comments and order kept, checked before
writing, written atomically). A site given on the command line (``--site``) or already in the
file counts as saved: the page does not ask.
"""

from __future__ import annotations

from pathlib import Path

from scopelink.astro import Site
from scopelink.cli.config import ConfigError
from scopelink.cli.config_edit import set_values
from scopelink.web.site_check import SiteStoreError

__all__ = ["SettingsSiteStore"]


class SettingsSiteStore:
    """A :class:`scopelink.web.site_check.SiteStore` on the settings file at ``path``."""

    def __init__(self, path: Path, *, saved: bool) -> None:
        self._path = path
        self._saved = saved

    @property
    def saved(self) -> bool:
        return self._saved

    @property
    def where(self) -> str:
        return str(self._path)

    def save(self, site: Site) -> None:
        try:
            set_values(
                self._path,
                [
                    ("site.latitude", repr(site.latitude_deg)),
                    ("site.longitude", repr(site.longitude_deg)),
                    ("site.elevation", repr(site.elevation_m)),
                ],
            )
        except ConfigError as error:
            raise SiteStoreError(str(error)) from None
        self._saved = True
