"""The pointing model's arithmetic (scopelink.mount.pointing_model), checked against the
simulator's misaligned sky, which is written apart from it (scopelink.sim.misalignment)."""

from __future__ import annotations

import math

import pytest

from scopelink.astro import angular_separation_deg
from scopelink.mount.pointing_model import (
    ALTAZ_TERMS,
    EQUATORIAL_TERMS,
    FittedModel,
    ModelFrame,
    fit,
)
from scopelink.sim.misalignment import Misalignment, parse_misalignment

LATITUDE = 48.0
SPREAD = [(30.0, 20.0), (60.0, 100.0), (45.0, 180.0), (25.0, 250.0), (70.0, 300.0), (40.0, 340.0)]


def arcmin(a: tuple[float, float], b: tuple[float, float]) -> float:
    return float(angular_separation_deg(a[1], a[0], b[1], b[0])) * 60.0


@pytest.mark.parametrize("equatorial", [True, False], ids=["equatorial", "altaz"])
def test_six_spread_syncs_recover_a_five_degree_misalignment_exactly(equatorial: bool) -> None:
    sky = Misalignment(2.0, -1.5, 3.0, -2.5)
    readings = [sky.reading_of(*t, LATITUDE, equatorial=equatorial) for t in SPREAD]
    model = fit(ModelFrame(equatorial, LATITUDE), readings, SPREAD)
    assert model.fitted == (EQUATORIAL_TERMS if equatorial else ALTAZ_TERMS)
    terms = model.terms_arcmin()
    names = model.frame.terms
    expected = {names[0]: 120.0, names[1]: -90.0, names[2]: 0.0}
    if equatorial:
        expected |= {"MA": 180.0, "ME": -150.0}
    else:  # the base tilted about the east-west axis (AN) and the north-south axis (AW)
        expected |= {"AN": -150.0, "AW": 180.0}
    for name, value in expected.items():
        assert terms[name] == pytest.approx(value, abs=1e-4), name
    for true in [(35.0, 60.0), (80.0, 10.0), (20.0, 200.0)]:
        reading = sky.reading_of(*true, LATITUDE, equatorial=equatorial)
        assert arcmin(model.true_of(*reading), true) < 1e-4
        assert arcmin(model.reading_of(*true), reading) < 1e-4


@pytest.mark.parametrize("equatorial", [True, False], ids=["equatorial", "altaz"])
def test_true_of_is_the_exact_inverse_of_reading_of(equatorial: bool) -> None:
    model = FittedModel(ModelFrame(equatorial, LATITUDE), (0.03, -0.02, 0.004, 0.05, -0.04), ())
    for true in [(10.0, 5.0), (45.0, 91.0), (84.0, 270.0), (60.0, 359.5)]:
        assert arcmin(model.true_of(*model.reading_of(*true)), true) < 1e-6


def test_the_collimation_term_is_fitted() -> None:
    cone = FittedModel(ModelFrame(True, LATITUDE), (0.0, 0.0, math.radians(0.5), 0.0, 0.0), ())
    readings = [cone.reading_of(*t) for t in SPREAD]
    model = fit(ModelFrame(True, LATITUDE), readings, SPREAD)
    assert model.terms_arcmin()["CH"] == pytest.approx(30.0, abs=1e-4)


def test_one_sync_fits_the_smallest_turn_that_moves_nothing_farther_than_the_sync() -> None:
    """One sync at Dec ~70°: zero points in hour angle would move the equator three times as
    far; the turn moves no position farther than the sync itself."""
    reading, true = (70.0, 0.0), (73.0, 2.0)
    model = fit(ModelFrame(True, LATITUDE), [reading], [true])
    assert len(model.fitted) == 3
    assert arcmin(model.true_of(*reading), true) < 1e-3
    step = arcmin(reading, true)
    for alt in range(0, 90, 10):
        for az in range(0, 360, 30):
            here = (float(alt), float(az))
            assert arcmin(model.reading_of(*here), here) <= step + 1e-3


def test_syncs_bunched_together_fit_the_turn_only() -> None:
    sky = Misalignment(1.0, 1.0, 1.0, 1.0)
    bunched = [(45.0, 180.0), (45.5, 180.5), (46.0, 181.0), (45.2, 181.2)]
    readings = [sky.reading_of(*t, LATITUDE, equatorial=True) for t in bunched]
    model = fit(ModelFrame(True, LATITUDE), readings, bunched)
    assert model.fitted == ("IH", "MA", "ME")


def test_the_emulator_misalignment_option_is_checked() -> None:
    assert parse_misalignment("1.5,-2,3,-1") == Misalignment(1.5, -2.0, 3.0, -1.0)
    for bad in ["1,2,3", "1,2,3,x", "1,2,3,11", "nan,0,0,0"]:
        with pytest.raises(ValueError, match="four numbers of degrees within ±10"):
            parse_misalignment(bad)


def test_the_documented_figures_are_the_code_s() -> None:
    """docs/pointing.md states the model's limits and defaults; they are the code's."""
    from pathlib import Path

    from scopelink.mount import pointing, pointing_model

    docs = (Path(__file__).parents[2] / "docs" / "pointing.md").read_text(encoding="utf-8")
    assert f"`FULL_MODEL_MIN_SYNCS` = {pointing_model.FULL_MODEL_MIN_SYNCS}" in docs
    assert f"`REPLACE_WITHIN_DEG` = {pointing.REPLACE_WITHIN_DEG:g}°" in docs
    assert f"capped at {pointing_model._SEC_CAP_DEG:g}°" in docs
    assert "condition number above 10⁴" in docs
    assert pointing_model._MAX_CONDITION == 1.0e4
    assert f"record `{pointing.POINTING_RECORD}`" in docs
