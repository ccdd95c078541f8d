"""Catalogue positions: deep-sky and star coordinates against published values, and stellar
proper motion against astropy's space motion (offline)."""

from __future__ import annotations

import math
from datetime import UTC, datetime

import erfa
import numpy as np
import pytest

from scopelink.astro.angles import parse_degrees, parse_hours
from scopelink.astro.catalog import ObjectKind, find, lookup
from scopelink.astro.timescales import tt_jd

J2000 = datetime(2000, 1, 1, 11, 58, 55, 816000, tzinfo=UTC)  # J2000.0 = 2000-01-01 12:00 TT
IN_2026 = datetime(2026, 6, 1, tzinfo=UTC)


def separation_arcsec(ra1_h: float, dec1_deg: float, ra2_h: float, dec2_deg: float) -> float:
    radians = erfa.seps(
        math.radians(ra1_h * 15), math.radians(dec1_deg), math.radians(ra2_h * 15),
        math.radians(dec2_deg),
    )  # fmt: skip
    return math.degrees(float(radians)) * 3600


def test_j2000_reference_instant_is_j2000_in_tt() -> None:
    jd1, jd2 = tt_jd(J2000)
    assert jd1 + jd2 == pytest.approx(2451545.0, abs=1e-8)


@pytest.mark.parametrize(
    ("name", "ra", "dec", "tolerance_arcsec"),
    [
        # M 31 nucleus (the brief's reference, SIMBAD to 0.1 s / 1")
        ("M 31", "00h42m44.3s", "+41°16'09\"", 1.5),
        # M 42: SIMBAD's 05 35 17.3 -05 23 28; OpenNGC puts the centre 13" away (extended object)
        ("M 42", "05h35m17.3s", "-05°23'28\"", 20.0),
        ("NGC 7000", "20h59m17.1s", "+44°31'44\"", 1.5),
        # the halves of the Double Cluster: cluster centres differ between catalogues by ~2'
        ("NGC 869", "02h19m00s", "+57°07'42\"", 180.0),
        ("NGC 884", "02h22m18s", "+57°08'12\"", 180.0),
    ],
)
def test_deep_sky_positions_match_published_j2000(
    name: str, ra: str, dec: str, tolerance_arcsec: float
) -> None:
    found = lookup(name, IN_2026)
    assert found.kind is ObjectKind.DEEP_SKY
    error = separation_arcsec(found.ra_hours, found.dec_deg, parse_hours(ra), parse_degrees(dec))
    assert error < tolerance_arcsec


def test_caldwell_14_is_the_double_cluster_between_ngc_869_and_884() -> None:
    double = lookup("Caldwell 14", IN_2026)
    assert "Double Cluster" in double.aliases
    assert "h & chi Persei" in double.aliases
    h_persei, chi_persei = lookup("NGC 869", IN_2026), lookup("NGC 884", IN_2026)
    assert "h Persei Cluster" in h_persei.aliases
    assert "chi Persei Cluster" in chi_persei.aliases
    halves = separation_arcsec(
        h_persei.ra_hours, h_persei.dec_deg, chi_persei.ra_hours, chi_persei.dec_deg
    )
    for half in (h_persei, chi_persei):
        to_half = separation_arcsec(double.ra_hours, double.dec_deg, half.ra_hours, half.dec_deg)
        assert to_half < halves


def test_deep_sky_records_carry_magnitude_and_constellation() -> None:
    andromeda = lookup("M 31", IN_2026)
    assert andromeda.magnitude == pytest.approx(3.44)
    assert andromeda.constellation == "And"
    assert andromeda.type_description == "Galaxy"
    assert andromeda.distance_au is None


@pytest.mark.parametrize(
    ("name", "ra", "dec"),
    [
        ("Vega", "18h36m56.3s", "+38°47'01\""),  # the brief's J2000 reference
        ("Polaris", "02h31m49.09s", "+89°15'50.8\""),  # SIMBAD (Hipparcos 2), epoch J2000
        ("Sirius", "06h45m08.92s", "-16°42'58.0\""),
        ("Betelgeuse", "05h55m10.31s", "+07°24'25.4\""),
    ],
)
def test_star_positions_at_j2000(name: str, ra: str, dec: str) -> None:
    found = lookup(name, J2000)
    assert found.kind is ObjectKind.STAR
    assert (
        separation_arcsec(found.ra_hours, found.dec_deg, parse_hours(ra), parse_degrees(dec)) < 1.0
    )


def _astropy_space_motion(hip_record: dict[str, float], when: datetime) -> tuple[float, float]:
    import astropy.units as u
    from astropy.coordinates import Distance, SkyCoord
    from astropy.time import Time

    star = SkyCoord(
        ra=hip_record["ra_rad"] * u.rad,
        dec=hip_record["dec_rad"] * u.rad,
        pm_ra_cosdec=hip_record["pm_ra_cosdec"] * u.mas / u.yr,
        pm_dec=hip_record["pm_dec"] * u.mas / u.yr,
        distance=Distance(parallax=hip_record["parallax"] * u.mas),
        radial_velocity=0 * u.km / u.s,
        obstime=Time(1991.25, format="jyear", scale="tt"),
    )
    moved = star.apply_space_motion(new_obstime=Time(when).tt)
    return float(moved.ra.hour), float(moved.dec.deg)


# Hipparcos new reduction (ESA I/311) records, typed from the catalogue, for an independent check.
VEGA = {
    "ra_rad": 4.8735545728,
    "dec_rad": 0.6768909262,
    "parallax": 130.23,
    "pm_ra_cosdec": 200.94,
    "pm_dec": 286.23,
}
BARNARDS_STAR = {  # HIP 87937: the largest proper motion, 10"/year
    "ra_rad": 4.7028598776,
    "dec_rad": 0.0814769927,
    "parallax": 548.31,
    "pm_ra_cosdec": -798.58,
    "pm_dec": 10328.12,
}


@pytest.mark.filterwarnings("ignore:ERFA function.*dubious year")  # 2050 is past the leap table
@pytest.mark.parametrize("when", [J2000, IN_2026, datetime(2050, 1, 1, tzinfo=UTC)])
@pytest.mark.parametrize(("name", "record"), [("Vega", VEGA), ("HIP 87937", BARNARDS_STAR)])
def test_proper_motion_matches_astropy_space_motion(
    name: str, record: dict[str, float], when: datetime
) -> None:
    found = lookup(name, when)
    expected = _astropy_space_motion(record, when)
    assert separation_arcsec(found.ra_hours, found.dec_deg, *expected) < 0.01


def test_vega_moves_by_its_proper_motion_between_2000_and_2026() -> None:
    then, now = lookup("Vega", J2000), lookup("Vega", IN_2026)
    moved = separation_arcsec(then.ra_hours, then.dec_deg, now.ra_hours, now.dec_deg)
    years = 26.42
    assert moved == pytest.approx(math.hypot(200.94, 286.23) / 1000 * years, rel=0.01)
    assert now.dec_deg > then.dec_deg  # north-east-ward motion
    assert now.ra_hours > then.ra_hours


def test_positions_of_a_star_work_on_arrays_of_times() -> None:
    vega = find("Vega")
    jd1 = np.full(3, 2451545.0)
    jd2 = np.array([0.0, 3652.5, 9496.5])
    ra, dec, distance = vega.position.astrometric((jd1, jd2), None)
    assert ra.shape == dec.shape == (3,)
    assert np.all(np.diff(dec) > 0)
    assert np.all(np.isnan(distance))


def test_named_star_magnitude_is_visual() -> None:
    assert lookup("Vega", IN_2026).magnitude == pytest.approx(0.03)
    assert lookup("Sirius", IN_2026).magnitude == pytest.approx(-1.44)
