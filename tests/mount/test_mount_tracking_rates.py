"""Mount.set_tracking_rates on the simulator: validation, and the dead-man (issue #16)."""

from __future__ import annotations

import pytest

from scopelink.astro import Site
from scopelink.mount import InvalidValueError, NotConnectedError, ParkedError
from scopelink.mount.rates import (
    SI_SECONDS_PER_SIDEREAL_SECOND,
    ra_rate_from_ascom,
    ra_rate_to_ascom,
)
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(latitude_deg=50.0, longitude_deg=10.0, elevation_m=300.0)


def _zero(mount: SimulatedMount) -> bool:
    """Whether no custom rate is in force (a call, so mypy does not narrow it across awaits)."""
    return mount.tracking_rates.zero


def _mount() -> SimulatedMount:
    return SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped())


def test_ascom_ra_rate_is_seconds_of_ra_per_sidereal_second() -> None:
    # One second of RA per sidereal second is 15″ of RA per sidereal second, so a little more
    # per SI second (a sidereal second is 0.99727 SI seconds).
    assert ra_rate_from_ascom(1.0) == pytest.approx(15.0 / 0.9972695677, rel=1e-8)
    assert pytest.approx(0.9972695677, rel=1e-8) == SI_SECONDS_PER_SIDEREAL_SECOND
    assert ra_rate_to_ascom(ra_rate_from_ascom(0.123)) == pytest.approx(0.123)


@pytest.mark.parametrize(
    ("ra", "dec", "message"),
    [
        (float("nan"), 0.0, "finite"),
        (0.0, float("inf"), "finite"),
        (3601.0, 0.0, "within ±3600"),
        (0.0, -1e9, "within ±3600"),
        ("fast", 0.0, "number"),
    ],
)
async def test_bad_rates_are_refused_in_one_line(ra: object, dec: object, message: str) -> None:
    mount = _mount()
    await mount.connect()
    with pytest.raises(InvalidValueError, match=message) as refused:
        await mount.set_tracking_rates(ra, dec)  # type: ignore[arg-type]
    assert "\n" not in str(refused.value)
    assert mount.tracking_rates.zero


async def test_rates_need_a_connected_unparked_mount() -> None:
    mount = _mount()
    with pytest.raises(NotConnectedError):
        await mount.set_tracking_rates(1.0, 0.0)
    await mount.connect()
    await mount.park()
    mount.clock.advance(300.0)
    await mount.refresh()
    with pytest.raises(ParkedError):
        await mount.set_tracking_rates(1.0, 0.0)
    await mount.set_tracking_rates(0.0, 0.0)  # back to the mode's rate: always allowed


async def test_the_dead_man_resets_the_rates_of_a_client_that_leaves() -> None:
    mount = _mount()
    await mount.connect()
    async with mount.motion_client("phone"):
        await mount.set_tracking_rates(20.0, -5.0)
        assert not _zero(mount)
    assert _zero(mount)
    # Rates set by nobody in particular (a script, Alpaca) outlive any client.
    await mount.set_tracking_rates(20.0, -5.0)
    async with mount.motion_client("other"):
        pass
    assert mount.tracking_rates.ra_arcsec_per_s == 20.0
