"""Custom tracking rates through Alpaca (issue #16): alpyca against the simulator.

The pointing is read from the simulated mount itself (its J2000 position at its own clock's
instants), and compared with the ideal: the start position integrated at the requested rates.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from alpaca.exceptions import InvalidOperationException, InvalidValueException
from alpaca.telescope import DriveRates, Telescope

from scopelink.astro import LUNAR_RATE_DEG_S, SIDEREAL_RATE_DEG_S, angular_separation_deg
from scopelink.mount import Limits, TrackingMode
from scopelink.mount.rates import ra_rate_from_ascom
from scopelink.sim import SimulatedMount
from tests.support.alpaca import blocking, client, radec_at, serve, sim_mount, wait_until

SLEW_TIMEOUT_S = 20.0


async def _connect_and_point(
    telescope: Telescope, mount: SimulatedMount, alt_deg: float, az_deg: float
) -> None:
    await blocking(lambda: setattr(telescope, "Connected", True))
    ra, dec = radec_at(mount, alt_deg, az_deg)
    await mount.goto_equatorial(ra, dec)
    await mount.wait_for_slew(SLEW_TIMEOUT_S)


def _j2000(mount: SimulatedMount) -> tuple[float, float, float]:
    """(elapsed s, RA h, Dec °) of one exact reading of the simulator."""
    t = mount.elapsed()
    ra, dec = mount.j2000_at(t)
    return t, ra, dec


def _error_arcsec(
    start: tuple[float, float, float],
    end: tuple[float, float, float],
    ra_arcsec_s: float,
    dec_arcsec_s: float,
) -> float:
    """How far ``end`` is from ``start`` integrated at the rates (arcsec on the sky)."""
    dt = end[0] - start[0]
    ideal_ra = start[1] + ra_arcsec_s * dt / 54000.0
    ideal_dec = start[2] + dec_arcsec_s * dt / 3600.0
    return 3600.0 * angular_separation_deg(ideal_ra * 15.0, ideal_dec, end[1] * 15.0, end[2])


async def test_lunar_rate_follows_the_moons_mean_motion(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect_and_point(telescope, mount, 45.0, 150.0)
        await blocking(lambda: setattr(telescope, "TrackingRate", DriveRates.driveLunar))
        start = _j2000(mount)
        await wait_until(lambda: mount.elapsed() - start[0] > 300.0, 30.0, "300 s of tracking")
        end = _j2000(mount)
        lunar_offset = (SIDEREAL_RATE_DEG_S - LUNAR_RATE_DEG_S) * 3600.0  # RA grows: east
        error = _error_arcsec(start, end, lunar_offset, 0.0)
        assert error < 0.5, (
            f"lunar tracking {error:.3f}″ from the ideal after {end[0] - start[0]:.0f} s"
        )
        assert (end[1] - start[1]) * 54000.0 > 100.0, "the RA did not drift east"


async def test_custom_ra_and_dec_rates_are_followed_exactly(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect_and_point(telescope, mount, 50.0, 200.0)
        assert await blocking(lambda: telescope.CanSetRightAscensionRate) is True
        assert await blocking(lambda: telescope.CanSetDeclinationRate) is True
        ra_ascom = 0.05  # seconds of RA per sidereal second (a fast comet)
        await blocking(lambda: setattr(telescope, "RightAscensionRate", ra_ascom))
        await blocking(lambda: setattr(telescope, "DeclinationRate", -2.5))
        assert await blocking(lambda: telescope.RightAscensionRate) == pytest.approx(ra_ascom)
        assert await blocking(lambda: telescope.DeclinationRate) == pytest.approx(-2.5)
        ra_arcsec_s = ra_rate_from_ascom(ra_ascom)
        assert mount.tracking_rates.ra_arcsec_per_s == pytest.approx(ra_arcsec_s)
        start = _j2000(mount)
        await wait_until(lambda: mount.elapsed() - start[0] > 300.0, 30.0, "300 s of tracking")
        end = _j2000(mount)
        error = _error_arcsec(start, end, ra_arcsec_s, -2.5)
        assert error < 0.5, f"custom rates {error:.3f}″ from the ideal"
        assert (start[2] - end[2]) * 3600.0 > 500.0, "the Dec did not move south"
        # Back to zero: sidereal again.
        await blocking(lambda: setattr(telescope, "RightAscensionRate", 0.0))
        await blocking(lambda: setattr(telescope, "DeclinationRate", 0.0))
        start = _j2000(mount)
        await wait_until(lambda: mount.elapsed() - start[0] > 100.0, 30.0, "100 s of tracking")
        assert _error_arcsec(start, _j2000(mount), 0.0, 0.0) < 0.5


async def test_refusals_are_one_line_and_change_nothing(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect_and_point(telescope, mount, 50.0, 200.0)
        with pytest.raises(InvalidValueException, match="within"):
            await blocking(lambda: setattr(telescope, "DeclinationRate", 1e5))
        # An RA offset set at sidereal does not ride on top of lunar: leaving sidereal zeroes
        # it (it is an offset from sidereal); the Dec rate is kept.
        await blocking(lambda: setattr(telescope, "RightAscensionRate", 0.01))
        await blocking(lambda: setattr(telescope, "DeclinationRate", 2.0))
        await blocking(lambda: setattr(telescope, "TrackingRate", DriveRates.driveLunar))
        assert await blocking(lambda: telescope.RightAscensionRate) == 0.0
        assert mount.tracking_rates.ra_arcsec_per_s == 0.0
        assert mount.tracking_rates.dec_arcsec_per_s == 2.0
        await blocking(lambda: setattr(telescope, "DeclinationRate", 0.0))
        with pytest.raises(InvalidOperationException, match="sidereal"):
            await blocking(lambda: setattr(telescope, "RightAscensionRate", 0.01))
        assert mount.tracking_rates.zero
        assert mount.state.tracking is TrackingMode.LUNAR
        await blocking(lambda: setattr(telescope, "TrackingRate", DriveRates.driveKing))
        assert DriveRates.driveKing in await blocking(lambda: list(telescope.TrackingRates))


async def test_a_custom_rate_towards_the_horizon_stops_above_it(tmp_path: Path) -> None:
    limits = Limits(horizon_deg=20.0)
    mount = sim_mount(limits=limits)
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect_and_point(telescope, mount, 30.0, 180.0)
        await blocking(lambda: setattr(telescope, "DeclinationRate", -600.0))  # south: down
        await wait_until(
            lambda: mount.state.tracking is TrackingMode.OFF, 30.0, "the stop at the horizon"
        )
        alt = mount.observed_at(mount.elapsed())[0]
        assert alt >= limits.horizon_deg - 0.05, f"stopped at {alt:.3f}°, below the horizon"
        assert alt < 21.0, f"stopped at {alt:.3f}°, far above the horizon: did it move at all?"
