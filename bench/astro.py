"""J2000 -> observed Alt/Az for 10,000 positions: scopelink's vectorised ERFA path beside astropy
(an independent implementation, measured in the same run on the same positions) and beside our
own scalar path called once per position (what a naive per-object loop costs).

Run ``.venv/bin/python -m bench.astro`` (a few seconds) or with ``--quick`` (the smoke test).
astropy is a test dependency; it runs offline with its bundled Earth-orientation data.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from datetime import UTC, datetime

import numpy as np

from scopelink.astro import Site, j2000_to_observed

SITE = Site(51.4779, -0.0015, 46.0)
WHEN = datetime(2026, 11, 22, 22, 0, tzinfo=UTC)


def positions(count: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(2026)
    ra_hours = rng.uniform(0.0, 24.0, count)
    dec_deg = np.degrees(np.arcsin(rng.uniform(-1.0, 1.0, count)))
    return ra_hours, dec_deg


def best_of(repeats: int, work: Callable[[], object]) -> float:
    """The fastest of ``repeats`` timings (seconds): the least disturbed by a shared machine."""
    timings = []
    for _ in range(repeats):
        started = time.perf_counter()
        work()
        timings.append(time.perf_counter() - started)
    return min(timings)


def astropy_altaz(ra_hours: np.ndarray, dec_deg: np.ndarray) -> Callable[[], object]:
    import astropy.units as u
    from astropy.coordinates import AltAz, EarthLocation, SkyCoord
    from astropy.time import Time
    from astropy.utils import iers

    iers.conf.auto_download = False
    iers.conf.auto_max_age = None
    location = EarthLocation.from_geodetic(
        SITE.longitude_deg * u.deg, SITE.latitude_deg * u.deg, SITE.elevation_m * u.m
    )
    frame = AltAz(
        obstime=Time(WHEN),
        location=location,
        pressure=SITE.effective_pressure_hpa * u.hPa,
        temperature=SITE.temperature_c * u.deg_C,
        relative_humidity=SITE.relative_humidity,
        obswl=0.55 * u.micron,
    )
    sky = SkyCoord(ra=ra_hours * u.hourangle, dec=dec_deg * u.deg, frame="icrs")
    return lambda: sky.transform_to(frame)


def main(count: int, repeats: int) -> None:
    ra, dec = positions(count)
    ours = best_of(repeats, lambda: j2000_to_observed(ra, dec, WHEN, SITE))
    scalar_sample = min(count, 500)
    scalar = best_of(
        1,
        lambda: [
            j2000_to_observed(float(r), float(d), WHEN, SITE)
            for r, d in zip(ra[:scalar_sample], dec[:scalar_sample], strict=True)
        ],
    ) * (count / scalar_sample)
    peer = best_of(repeats, astropy_altaz(ra, dec))
    peer_sample = 20
    peer_scalar = best_of(
        1,
        lambda: [astropy_altaz(ra[i : i + 1], dec[i : i + 1])() for i in range(peer_sample)],
    ) * (count / peer_sample)
    rows = [
        ("scopelink j2000_to_observed (vector)", ours),
        ("astropy SkyCoord.transform_to(AltAz) (vector)", peer),
        (
            f"scopelink, one call per position (x{count // scalar_sample} of {scalar_sample})",
            scalar,
        ),
        (f"astropy, one call per position (x{count // peer_sample} of {peer_sample})", peer_scalar),
    ]
    print(f"J2000 -> observed Alt/Az, {count} positions, best of {repeats}")
    print(f"{'path':<52} {'ms':>9} {'us/pos':>8} {'vs ours':>8}")
    for name, seconds in rows:
        print(
            f"{name:<52} {seconds * 1e3:9.2f} {seconds / count * 1e6:8.2f} {seconds / ours:7.1f}x"
        )
    print(
        f"astropy / scopelink: {peer / ours:.2f}x vectorised, {peer_scalar / scalar:.1f}x per call"
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="1,000 positions, 2 repeats")
    options = parser.parse_args()
    if options.quick:
        main(1_000, 2)
    else:
        main(10_000, 5)
