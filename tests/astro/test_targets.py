"""Moving targets (scopelink.astro.targets) against published figures and an independent
implementation: Meeus's comet Encke, Vallado's SGP4 verification vector, astropy's TEME frame
for a satellite's topocentric place, and one-line errors for bad files."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pytest

from scopelink.astro import Site, angular_separation_deg, j2000_to_observed, parse_degrees
from scopelink.astro.catalog import lookup
from scopelink.astro.targets import (
    TargetError,
    TargetKind,
    next_pass,
    orbit_target,
    satellite_target,
    solar_system_target,
    times_after,
)
from tests.support.targets import COMETS, SATELLITES

GREENWICH = Site(51.4779, -0.0015)


def _apart_arcsec(a: tuple[float, float], b: tuple[float, float]) -> float:
    return 3600.0 * angular_separation_deg(a[0] * 15.0, a[1], b[0] * 15.0, b[1])


def test_encke_matches_meeus_example_33a_in_both_formats() -> None:
    # Meeus, Astronomical Algorithms (2nd ed.), Example 33.a: comet Encke, 1990 Oct 6.0 TD
    # (ΔT 57 s), geometric J2000 place corrected for light time: α 10h34m14.151s,
    # δ +19°09'31".
    t = datetime(1990, 10, 6, tzinfo=UTC) - timedelta(seconds=57)
    meeus = (10.0 + 34.0 / 60.0 + 14.151 / 3600.0, parse_degrees("+19 09 31"))
    xephem = orbit_target("2P/Encke (Meeus)", COMETS, None)  # XEphem line, geocentric
    assert xephem.kind is TargetKind.COMET
    assert _apart_arcsec(xephem.position(t), meeus) < 3.0
    # The same orbit as an MPC one-line (elements rounded to 4 decimals), and topocentric.
    mpc = orbit_target("2p", COMETS, None)
    assert mpc.name == "2P/Encke"
    assert _apart_arcsec(mpc.position(t), meeus) < 5.0
    topocentric = orbit_target("2P/Encke (Meeus)", COMETS, Site(0.0, 0.0))
    parallax = _apart_arcsec(topocentric.position(t), xephem.position(t))
    assert 0.5 < parallax < 8.8 / 0.824 + 0.1  # Δ = 0.824 au: at most 10.7″


def test_a_comet_by_its_designation_and_its_rates() -> None:
    comet = orbit_target("C/2023 A3", COMETS, GREENWICH)
    assert comet.name == "C/2023 A3 (Tsuchinshan-ATLAS)"
    assert orbit_target("tsuchinshan-atlas", COMETS, GREENWICH).name == comet.name
    t = datetime(2024, 10, 14, 18, tzinfo=UTC)
    rate = comet.rate(t)
    ra0, dec0 = comet.position(t)
    ra1, dec1 = comet.position(t + timedelta(minutes=10))
    assert rate.ra_arcsec_per_s == pytest.approx((ra1 - ra0) * 54000.0 / 600.0, rel=0.01)
    assert rate.dec_arcsec_per_s == pytest.approx((dec1 - dec0) * 3600.0 / 600.0, rel=0.01)
    assert rate.ra_arcsec_per_s > 0.1  # near Earth in October 2024: degrees a day


def test_moon_is_topocentric_with_its_rates_and_path() -> None:
    t = datetime(2026, 3, 3, 21, tzinfo=UTC)
    moon = solar_system_target("moon", GREENWICH)
    assert (moon.name, moon.kind) == ("Moon", TargetKind.MOON)
    catalogue = lookup("Moon", t, GREENWICH)
    assert _apart_arcsec(moon.position(t), (catalogue.ra_hours, catalogue.dec_deg)) < 0.01
    geocentric = solar_system_target("Moon", None).position(t)
    assert (
        0.1
        < angular_separation_deg(
            moon.position(t)[0] * 15, moon.position(t)[1], geocentric[0] * 15, geocentric[1]
        )
        < 1.0
    )  # parallax: up to ~1°
    rate = moon.rate(t)
    assert 0.3 < rate.ra_arcsec_per_s < 0.8  # ~13°/day eastwards, in seconds of RA ×15
    path = moon.path(t)
    assert len(path) == 60
    assert path[0] == pytest.approx((moon.position(t)[0] * 15.0, moon.position(t)[1]))
    assert solar_system_target("Jupiter", GREENWICH).kind is TargetKind.PLANET
    assert solar_system_target("sun", GREENWICH).kind is TargetKind.SUN
    with pytest.raises(TargetError, match="not a body of the solar system"):
        solar_system_target("M31", GREENWICH)
    with pytest.raises(TargetError, match="Jupiter"):
        solar_system_target("Jupitr", GREENWICH)


def test_sgp4_reproduces_vallado_and_topocentric_matches_astropy() -> None:
    from astropy import units as u
    from astropy.coordinates import ITRS, TEME, AltAz, CartesianRepresentation, EarthLocation
    from astropy.time import Time

    # Vallado, Crawford, Hujsak & Kelso, "Revisiting Spacetrack Report #3" (AIAA 2006-6753),
    # verification output for satellite 00005 at its epoch: r (TEME) in km.
    vanguard = satellite_target("00005", SATELLITES, GREENWICH)
    satrec = vanguard.tle.satrec
    _, r, _ = satrec.sgp4(satrec.jdsatepoch, satrec.jdsatepochF)
    assert r == pytest.approx((7022.46529266, -1400.08296755, 0.03995155), abs=1e-6)

    iss = satellite_target("ISS", SATELLITES, GREENWICH)
    assert iss.name == "ISS (ZARYA)"
    start = datetime(2008, 9, 20, 12, 25, 40, tzinfo=UTC)
    offsets = np.arange(0.0, 86400.0, 600.0)
    jd = times_after(start, offsets)
    alt, az = iss.altaz(jd)
    _, teme, _ = iss.tle.satrec.sgp4_array(*jd)
    when = Time(jd[0], jd[1], format="jd", scale="ut1")  # as the package: UT1 = UTC
    frame = TEME(CartesianRepresentation(teme.T * u.km), obstime=when)
    site = EarthLocation.from_geodetic(GREENWICH.longitude_deg, GREENWICH.latitude_deg, 0.0)
    # astropy's way for a nearby object: topocentric ITRS, then AltAz.
    fixed = frame.transform_to(ITRS(obstime=when)).cartesian
    topocentric = ITRS(fixed - site.get_itrs(when).cartesian, obstime=when, location=site)
    reference = topocentric.transform_to(AltAz(obstime=when, location=site))
    d_alt = np.abs(alt - reference.alt.deg) * 3600.0
    d_az = np.abs((az - reference.az.deg + 180.0) % 360.0 - 180.0) * np.cos(np.radians(alt))
    d_az = d_az * 3600.0
    assert d_alt.max() < 5.0
    assert d_az.max() < 5.0
    # The J2000-equivalent place maps back onto the geometric direction (refraction off).
    ra, dec = iss.positions(jd)
    back_alt, _back_az = j2000_to_observed(ra, dec, jd, GREENWICH.without_refraction())
    assert np.abs(back_alt - alt).max() * 3600.0 < 0.01


def test_a_pass_rises_culminates_and_sets() -> None:
    iss = satellite_target("25544", SATELLITES, GREENWICH)
    start = datetime(2008, 9, 20, 12, 25, 40, tzinfo=UTC)
    found = next_pass(iss, start)
    assert found is not None
    assert start < found.rise < found.culmination < found.set
    assert 120.0 < found.duration_s < 12 * 60.0

    def alt(t: datetime) -> float:
        return float(iss.altaz(times_after(t, np.zeros(1)))[0][0])

    assert abs(alt(found.rise)) < 0.01
    assert abs(alt(found.set)) < 0.01
    assert alt(found.culmination) == pytest.approx(found.max_alt_deg, abs=1e-6)
    for side in (-5.0, 5.0):
        assert alt(found.culmination + timedelta(seconds=side)) < found.max_alt_deg
    high = next_pass(iss, start, horizon_deg=found.max_alt_deg + 0.5, window_hours=3)
    assert high is None or high.rise > found.set


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "ISS\n1 25544U 98067A   08264.51782528 -.00002182  00000-0 -11606-4 0  2928\n"
            "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537\n",
            "line 2: TLE checksum does not match",
        ),
        ("ISS\n1 25544U 98067A   08264.51782528\n", "line 2: not line 1 of a TLE"),
        ("just some words\n", "holds no TLE"),
    ],
)
def test_bad_tle_files_give_one_line(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.tle"
    path.write_text(text)
    with pytest.raises(TargetError, match=message) as caught:
        satellite_target("ISS", path, GREENWICH)
    assert "\n" not in str(caught.value)


def test_bad_elements_and_names_give_one_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.txt"
    path.write_text("# comment\nC/2099 Z9,e,notanumber\n")
    with pytest.raises(TargetError, match="line 2: not an MPC one-line or XEphem orbit"):
        orbit_target("C/2099 Z9", path, GREENWICH)
    path.write_text("too short\n")
    with pytest.raises(TargetError, match="line 1"):
        orbit_target("x", path, GREENWICH)
    with pytest.raises(TargetError, match=r"no orbit called 'Halley' .*C/2023 A3"):
        orbit_target("Halley", COMETS, GREENWICH)
    with pytest.raises(TargetError, match="cannot read elements file"):
        orbit_target("Halley", tmp_path / "missing.txt", GREENWICH)
    with pytest.raises(TargetError, match=r"no satellite called 'Hubble' .*ISS \(ZARYA\)"):
        satellite_target("Hubble", SATELLITES, GREENWICH)


def test_an_mpcorb_asteroid_line_reads_as_its_xephem_twin() -> None:
    t = datetime(2024, 12, 1, tzinfo=UTC)
    mpc = orbit_target("Ceres", COMETS, GREENWICH)
    assert (mpc.name, mpc.kind) == ("(1) Ceres", TargetKind.ASTEROID)
    assert orbit_target("1", COMETS, GREENWICH).name == "(1) Ceres"
    xephem = orbit_target("(1) Ceres (XEphem)", COMETS, GREENWICH)
    assert _apart_arcsec(mpc.position(t), xephem.position(t)) < 0.1
