"""Comets and asteroids from orbital elements the user gives: MPC one-line or XEphem format.

The orbit is propagated by PyEphem (``ephem``, already a dependency: a two-body Kepler orbit from
the osculating elements, the method of every planetarium program for user elements), which gives
the astrometric geocentric J2000 place with light time; the site's parallax is added here (a
comet at 0.3 au is displaced by up to 30″). Formats read, one orbit per line:

- XEphem database lines (``name,e,...``, ``name,p,...``, ``name,h,...``), read by ``ephem.readdb``;
- MPC one-line comet elements (``CometEls.txt``: perihelion time and distance, e, ω, Ω, i);
- MPC one-line asteroid elements (``MPCORB.DAT``: packed epoch, M, ω, Ω, i, e, n, a).

Blank lines and lines starting with ``#`` are skipped. Times in MPC elements are TT; PyEphem reads
them as UT (a 69 s shift of the epoch: < 0.1″ on any comet's place).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import ephem
import erfa
import numpy as np

from scopelink.astro._arrays import FloatArray
from scopelink.astro.catalog.names import name_key
from scopelink.astro.catalog.solar_system import _site_gcrs_km
from scopelink.astro.site import Site
from scopelink.astro.targets.base import (
    MovingTarget,
    TargetError,
    TargetKind,
    read_target_file,
)
from scopelink.astro.timescales import tt_pair

__all__ = ["OrbitTarget", "orbit_target", "read_orbits"]

_AU_KM = 149597870.7
_GAUSS_DEG_PER_DAY = 0.9856076686
"""The Gaussian gravitational constant in degrees: a 1 au orbit's mean daily motion."""
_DUBLIN_JD = 2415020.0
"""PyEphem counts days from 1899 December 31 12:00 (JD 2415020)."""

MIN_PERIHELION_AU = 0.001
"""The closest perihelion an orbit may have (a fifth of the Sun's radius: no body orbits
closer). PyEphem's Kepler solver never returns for a perihelion of 0 or an orbit of infinite
size, so such elements are refused when read, before any place is computed."""

MAX_ORBIT_AU = 1.0e6
"""The largest semi-major axis or perihelion distance an orbit may have (beyond the Oort
cloud); larger or infinite values are typing errors."""


@dataclass(frozen=True, slots=True)
class Orbit:
    """One orbit read from a file: its name, XEphem line and whether it is a comet."""

    name: str
    xephem: str
    comet: bool


class OrbitTarget(MovingTarget):
    """A comet or asteroid on a Kepler orbit (PyEphem), topocentric for the site."""

    def __init__(self, orbit: Orbit, site: Site | None) -> None:
        super().__init__(orbit.name, TargetKind.COMET if orbit.comet else TargetKind.ASTEROID, site)
        self.orbit = orbit
        self._body = _checked_body(orbit.xephem)

    def positions(self, jd: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
        jd1, jd2 = (np.ravel(part) for part in jd)
        vectors = np.empty((3, jd1.size))
        for i, (a, b) in enumerate(zip(jd1, jd2, strict=True)):
            try:
                self._body.compute(ephem.Date((a - _DUBLIN_JD) + b))
                ra, dec = float(self._body.a_ra), float(self._body.a_dec)
                distance_km = float(self._body.earth_distance) * _AU_KM
            except (RuntimeError, ValueError, OverflowError) as error:  # PyEphem's refusals
                raise TargetError(f"{self.name}: no place from these elements ({error})") from None
            if not (math.isfinite(ra) and math.isfinite(dec) and math.isfinite(distance_km)):
                raise TargetError(f"{self.name}: these elements give no place (not a number)")
            vectors[:, i] = distance_km * np.array(
                [math.cos(dec) * math.cos(ra), math.cos(dec) * math.sin(ra), math.sin(dec)]
            )
        if self.site is not None:
            tt1, tt2 = tt_pair((jd1, jd2))
            vectors = vectors - _site_gcrs_km(self.site, (jd1, jd2), tt1, tt2)
        ra, dec = erfa.c2s(vectors.T)
        shape = np.shape(jd[0])
        return (
            np.mod(np.degrees(ra) / 15.0, 24.0).reshape(shape),
            np.degrees(dec).reshape(shape),
        )


def read_orbits(path: Path) -> list[Orbit]:
    """Every orbit in an elements file, or a one-line :class:`TargetError` naming the line."""
    text = read_target_file(path, "elements file")
    orbits = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            orbits.append(_orbit_of_line(line))
        except (ValueError, IndexError, ZeroDivisionError, OverflowError) as error:
            raise TargetError(
                f"{path} line {number}: not an MPC one-line or XEphem orbit ({error})"
            ) from None
    if not orbits:
        raise TargetError(f"{path} holds no orbital elements (MPC one-line or XEphem lines)")
    return orbits


def orbit_target(name: str, path: Path, site: Site | None) -> OrbitTarget:
    """The orbit called ``name`` in the elements file ``path`` ("C/2023 A3" finds
    "C/2023 A3 (Tsuchinshan-ATLAS)"; case and spaces do not matter)."""
    orbits = read_orbits(path)
    wanted = name_key(name)
    for orbit in orbits:
        if wanted in _keys(orbit.name):
            return OrbitTarget(orbit, site)
    names = ", ".join(orbit.name for orbit in orbits[:5])
    more = f" and {len(orbits) - 5} more" if len(orbits) > 5 else ""
    raise TargetError(f"no orbit called {name!r} in {path} (it has {names}{more})")


def _keys(full_name: str) -> set[str]:
    """The names an orbit answers to: whole, before the parenthesis, inside it, after it,
    a periodic comet's or an asteroid's number."""
    keys = {name_key(full_name)}
    before, _, inside = full_name.partition("(")
    keys.add(name_key(before))
    if inside:
        number, _, after = inside.partition(")")
        keys.add(name_key(number))  # "(433) Eros" answers to "433" and to "Eros"
        keys.add(name_key(after))
        keys.add(name_key(inside.rstrip(") ")))
    if "/" in before:
        keys.add(name_key(before.split("/")[0]))  # "12P/Pons-Brooks" answers to "12P"
    keys.discard("")
    return keys


def _checked_body(xephem: str) -> ephem.Body:
    """The PyEphem body of an XEphem line, or ``ValueError`` when it is no orbit PyEphem can
    carry: another XEphem type (a fixed star, an Earth satellite), an eccentricity that does not
    fit the orbit's type, or a perihelion or size outside [``MIN_PERIHELION_AU``,
    ``MAX_ORBIT_AU``] (PyEphem hangs on some of those)."""
    body = ephem.readdb(xephem)
    if isinstance(body, ephem.EllipticalBody):
        a, e = float(body._a), float(body._e)
        if not 0.0 <= e < 1.0:
            raise ValueError(f"an elliptical orbit needs an eccentricity in [0, 1), not {e:g}")
        _check_distance("semi-major axis", a)
        _check_distance("perihelion distance", a * (1.0 - e))
    elif isinstance(body, ephem.HyperbolicBody):
        e = float(body._e)
        if not (math.isfinite(e) and e > 1.0):
            raise ValueError(f"a hyperbolic orbit needs an eccentricity above 1, not {e:g}")
        _check_distance("perihelion distance", float(body._q))
    elif isinstance(body, ephem.ParabolicBody):
        _check_distance("perihelion distance", float(body._q))
    else:
        raise ValueError(f"an XEphem {type(body).__name__} is no orbit (types e, h or p are)")
    return body


def _check_distance(what: str, au: float) -> None:
    if not (math.isfinite(au) and MIN_PERIHELION_AU <= au <= MAX_ORBIT_AU):
        raise ValueError(
            f"{what} {au:g} au must lie within {MIN_PERIHELION_AU:g}-{MAX_ORBIT_AU:g} au"
        )


def _orbit_of_line(line: str) -> Orbit:
    if "," in line[:60]:
        body = _checked_body(line.strip())
        return Orbit(body.name, line.strip(), _xephem_is_comet(line))
    if len(line.rstrip()) >= 104 and re.match(r"^[ \d]{4}[CPDXAI]", line):
        return _mpc_comet(line)
    if len(line.rstrip()) >= 103:
        return _mpc_asteroid(line)
    raise ValueError("too short for MPC one-line elements, and no XEphem commas")


def _xephem_is_comet(line: str) -> bool:
    fields = line.strip().split(",")
    # Parabolic and hyperbolic orbits are comets; an elliptical one is a comet when named so.
    return fields[1].strip() in ("p", "h") or bool(re.match(r"^\s*(\d+[PCD]\b|[CPD]/)", fields[0]))


def _field(line: str, first: int, last: int) -> float:
    """The number in 1-based columns ``first``..``last``."""
    text = line[first - 1 : last].strip()
    if not text:
        raise ValueError(f"columns {first}-{last} are empty")
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"columns {first}-{last} hold {text!r}, not a number")
    return value


def _mpc_comet(line: str) -> Orbit:
    """MPC comet one-line: perihelion time (TT), q, e, ω, Ω, i (J2000), designation and name."""
    year, month, day = int(_field(line, 15, 18)), int(_field(line, 20, 21)), _field(line, 23, 29)
    q, e = _field(line, 31, 39), _field(line, 42, 49)
    peri, node, inc = _field(line, 52, 59), _field(line, 62, 69), _field(line, 72, 79)
    name = line[102:158].strip() or line[:12].strip()
    magnitude = line[91:100].split()
    h, k = magnitude if len(magnitude) == 2 else ("10", "4")
    when = f"{month}/{day}/{year}"
    _check_distance("perihelion distance", q)
    if not (math.isfinite(e) and e >= 0.0):
        raise ValueError(f"eccentricity {e:g} must be a number of at least 0")
    if e < 1.0:
        a = q / (1.0 - e)
        n = _GAUSS_DEG_PER_DAY / a**1.5
        xephem = f"{name},e,{inc},{node},{peri},{a},{n},{e},0,{when},2000,g{h},{k}"
    elif e == 1.0:
        xephem = f"{name},p,{when},{inc},{peri},{q},{node},2000,{h},{k}"
    else:
        xephem = f"{name},h,{when},{inc},{node},{peri},{e},{q},2000,{h},{k}"
    _checked_body(xephem)  # the values must make an orbit PyEphem takes
    return Orbit(name, xephem, comet=True)


_PACKED_CENTURY = {"I": 1800, "J": 1900, "K": 2000, "L": 2100}


def _packed_digit(char: str) -> int:
    """MPC packed month or day: 1-9, then A = 10 ... V = 31."""
    if char.isdigit():
        return int(char)
    if "A" <= char <= "V":
        return ord(char) - ord("A") + 10
    raise ValueError(f"bad packed date digit {char!r}")


def _mpc_asteroid(line: str) -> Orbit:
    """MPCORB one-line: H, G, packed epoch, M, ω, Ω, i, e, n, a, readable designation."""
    epoch = line[20:25]
    if len(epoch) != 5 or epoch[0] not in _PACKED_CENTURY:
        raise ValueError(f"packed epoch {epoch!r} in columns 21-25 is not like K24AH")
    year = _PACKED_CENTURY[epoch[0]] + int(epoch[1:3])
    month, day = _packed_digit(epoch[3]), _packed_digit(epoch[4])
    h = line[8:13].strip() or "10"
    g = line[14:19].strip() or "0.15"
    m, peri = _field(line, 27, 35), _field(line, 38, 46)
    node, inc = _field(line, 49, 57), _field(line, 60, 68)
    e, n, a = _field(line, 71, 79), _field(line, 81, 91), _field(line, 93, 103)
    name = line[166:194].strip() if len(line) > 166 else ""
    name = name or line[:7].strip()
    xephem = f"{name},e,{inc},{node},{peri},{a},{n},{e},{m},{month}/{day}/{year},2000,H{h},{g}"
    _checked_body(xephem)
    return Orbit(name, xephem, comet=False)
