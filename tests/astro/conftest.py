"""Fixtures of the astronomy tests."""

from __future__ import annotations

from collections.abc import Iterator

import pytest


@pytest.fixture(scope="module", autouse=True)
def offline_astropy() -> Iterator[None]:
    """astropy, the independent reference, stays offline: its bundled IERS data, no download."""
    from astropy.utils import iers

    with iers.conf.set_temp("auto_download", False), iers.conf.set_temp("auto_max_age", None):
        yield
