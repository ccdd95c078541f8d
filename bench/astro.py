"""J2000 -> observed Alt/Az: scopelink beside astropy (an independent implementation), same run.

Two comparisons, each row the best of N repeats (the least disturbed by a shared machine):

1. **Many positions at one instant** (a catalogue, a horizon mask): 10,000 random J2000 positions.
   Every repeat is at a new instant 60 s after the last, beyond the 10-s window in which our
   observer context is reused, so neither side reuses the star-independent work; astropy's
   frames and SkyCoord are built before the clock starts (only ``transform_to`` is timed).
2. **One position per call at changing instants** (a mount poll, an emulator reply): each call a
   new position at a new instant. Ours at 0.5-s steps (a poll's cadence: the context is reused,
   only the Earth rotation updated) and at 60-s steps (fresh contexts every call: ERFA's
   ``apci13`` + ``apio13``, the route of one float position, ``astro.one_position``);
   astropy with its frames built before the clock starts (its frame reused as far as astropy
   allows: a frame is tied to its obstime) and ``transform_to`` timed per call.

Goal (issue #14 part 4): ours at most astropy's time on every row of both comparisons. The
report ends with one verdict line per goal row, PASS or MISS. astropy is pinned (``PEER_PIN``):
another version is refused unless ``--any-peer-version`` is given, and then the report says so.

Run ``.venv/bin/python -m bench.astro`` (about a minute) or ``--quick`` (the smoke test).
astropy is a test dependency; it runs offline with its bundled Earth-orientation data.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any

import numpy as np

from bench.provenance import peer_label, pin_problem, print_provenance
from scopelink.astro import Site, j2000_to_observed

SITE = Site(51.4779, -0.0015, 46.0)
WHEN = datetime(2026, 11, 22, 22, 0, tzinfo=UTC)
PEER_PIN = "8.0.2"
"""The astropy version the published figures were measured with."""
POLL_STEP = timedelta(seconds=0.5)
FRESH_STEP = timedelta(seconds=60)


@dataclass(frozen=True)
class Sizes:
    positions: int
    repeats: int
    calls: int
    """single-position calls per repeat"""


FULL = Sizes(positions=10_000, repeats=15, calls=200)
QUICK = Sizes(positions=1_000, repeats=2, calls=10)


def positions(count: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(2026)
    ra_hours = rng.uniform(0.0, 24.0, count)
    dec_deg = np.degrees(np.arcsin(rng.uniform(-1.0, 1.0, count)))
    return ra_hours, dec_deg


def best_of(repeats: int, work: Callable[[int], object]) -> float:
    """The fastest of ``repeats`` timings (seconds); ``work`` gets the repeat's index."""
    timings = []
    for repeat in range(repeats):
        started = time.perf_counter()
        work(repeat)
        timings.append(time.perf_counter() - started)
    return min(timings)


class Astropy:
    """astropy's AltAz transform for SITE's air, frames built outside the timed region."""

    def __init__(self) -> None:
        import astropy.units as u
        from astropy.coordinates import AltAz, EarthLocation, SkyCoord
        from astropy.time import Time
        from astropy.utils import iers

        iers.conf.auto_download = False
        iers.conf.auto_max_age = None
        self._u, self._altaz, self._skycoord, self._time = u, AltAz, SkyCoord, Time
        self._location = EarthLocation.from_geodetic(
            SITE.longitude_deg * u.deg, SITE.latitude_deg * u.deg, SITE.elevation_m * u.m
        )

    def frame(self, moment: datetime) -> Any:
        u = self._u
        return self._altaz(
            obstime=self._time(moment),
            location=self._location,
            pressure=SITE.effective_pressure_hpa * u.hPa,
            temperature=SITE.temperature_c * u.deg_C,
            relative_humidity=SITE.relative_humidity,
            obswl=SITE.wavelength_um * u.micron,
        )

    def sky(self, ra_hours: np.ndarray, dec_deg: np.ndarray) -> Any:
        u = self._u
        return self._skycoord(ra=ra_hours * u.hourangle, dec=dec_deg * u.deg, frame="icrs")


def instants(start: datetime, step: timedelta, count: int) -> list[datetime]:
    return [start + step * i for i in range(count)]


def vector_rows(sizes: Sizes, peer: Astropy) -> tuple[float, float]:
    ra, dec = positions(sizes.positions)
    moments = instants(WHEN, FRESH_STEP, sizes.repeats)
    ours = best_of(sizes.repeats, lambda k: j2000_to_observed(ra, dec, moments[k], SITE))
    frames = [peer.frame(m) for m in instants(WHEN + timedelta(hours=1), FRESH_STEP, sizes.repeats)]
    sky = peer.sky(ra, dec)
    theirs = best_of(sizes.repeats, lambda k: sky.transform_to(frames[k]))
    return ours, theirs


def single_rows(sizes: Sizes, peer: Astropy) -> tuple[float, float, float]:
    """Seconds per call: ours at poll cadence, ours with a fresh context, astropy."""
    ra, dec = positions(sizes.calls)
    pairs = list(zip(ra.tolist(), dec.tolist(), strict=True))

    def ours(step: timedelta) -> Callable[[int], object]:
        def run(repeat: int) -> object:
            start = WHEN + timedelta(hours=2 + repeat)
            moments = instants(start, step, sizes.calls)
            return [
                j2000_to_observed(r, d, m, SITE) for (r, d), m in zip(pairs, moments, strict=True)
            ]

        return run

    polled = best_of(sizes.repeats, ours(POLL_STEP)) / sizes.calls
    fresh = best_of(sizes.repeats, ours(FRESH_STEP)) / sizes.calls
    prepared = [
        (
            [peer.sky(ra[i : i + 1], dec[i : i + 1]) for i in range(sizes.calls)],
            [
                peer.frame(m)
                for m in instants(WHEN + timedelta(hours=9 + k), POLL_STEP, sizes.calls)
            ],
        )
        for k in range(sizes.repeats)
    ]
    theirs = best_of(
        sizes.repeats,
        lambda k: [s.transform_to(f) for s, f in zip(prepared[k][0], prepared[k][1], strict=True)],
    )
    return polled, fresh, theirs / sizes.calls


def peer_lines() -> list[str]:
    import astropy
    import erfa

    return [
        f"peer {peer_label('astropy', astropy.__version__, PEER_PIN)}, pyerfa {erfa.__version__}, "
        f"numpy {np.__version__}",
    ]


def verdict(name: str, ours: float, theirs: float) -> str:
    outcome = "PASS" if ours <= theirs else "MISS"
    return f"goal {name}: ours <= astropy: {outcome} (astropy / ours = {theirs / ours:.2f}x)"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="1,000 positions, 2 repeats")
    parser.add_argument(
        "--any-peer-version", action="store_true", help=f"run with astropy other than {PEER_PIN}"
    )
    options = parser.parse_args(argv)
    import astropy

    problem = pin_problem("astropy", astropy.__version__, PEER_PIN, options.any_peer_version)
    if problem is not None:
        print(f"bench.astro: {problem}", file=sys.stderr)
        return 2
    sizes = QUICK if options.quick else FULL
    peer = Astropy()
    ours_vector, peer_vector = vector_rows(sizes, peer)
    polled, fresh, peer_single = single_rows(sizes, peer)
    print_provenance(*peer_lines())
    print()
    print(f"1. {sizes.positions} positions at one instant, best of {sizes.repeats}")
    print(f"   {'path':<56} {'ms':>9} {'us/pos':>8}")
    for name, seconds in (
        ("scopelink j2000_to_observed (arrays)", ours_vector),
        ("astropy SkyCoord.transform_to(AltAz) (arrays)", peer_vector),
    ):
        print(f"   {name:<56} {seconds * 1e3:9.2f} {seconds / sizes.positions * 1e6:8.3f}")
    print()
    print(
        f"2. one position per call at changing instants, {sizes.calls} calls, "
        f"best of {sizes.repeats}"
    )
    print(f"   {'path':<56} {'us/call':>9}")
    for name, seconds in (
        ("scopelink, instants 0.5 s apart (context reused)", polled),
        ("scopelink, instants 60 s apart (fresh contexts each)", fresh),
        ("astropy transform_to, frames pre-built, 0.5 s apart", peer_single),
    ):
        print(f"   {name:<56} {seconds * 1e6:9.1f}")
    print()
    print(verdict("1 (arrays)", ours_vector, peer_vector))
    print(verdict("2 (one per call, 0.5 s)", polled, peer_single))
    print(verdict("2 (one per call, 60 s)", fresh, peer_single))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
