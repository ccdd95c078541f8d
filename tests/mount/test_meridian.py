"""The meridian limits' judgement (``scopelink.mount.meridian``) and the checks of their values
(issue #15 part 3; the settings file and docs: tests/safety/test_safety_meridian_settings.py)."""

from __future__ import annotations

import pytest

from scopelink.astro import PierSide
from scopelink.mount import InvalidValueError, LimitError, Limits
from scopelink.mount.meridian import minutes_left, past_meridian_deg, plan_goto_side

EAST, WEST = PierSide.EAST, PierSide.WEST


def test_past_the_meridian_counts_the_counterweight_rising_on_either_side() -> None:
    assert past_meridian_deg(0.2, WEST) == pytest.approx(3.0)  # west of it, tube on the west
    assert past_meridian_deg(-0.2, WEST) == pytest.approx(-3.0)
    assert past_meridian_deg(-0.2, EAST) == pytest.approx(3.0)  # east of it, tube on the east
    assert past_meridian_deg(0.2, PierSide.UNKNOWN) is None
    # Below the pole (more than 6 h from the meridian) it counts the other way round.
    assert past_meridian_deg(11.9, WEST) == pytest.approx(-181.5)
    assert past_meridian_deg(-11.9, EAST) == pytest.approx(-181.5)


def test_minutes_left_to_the_west_limit_at_the_sidereal_rate() -> None:
    limits = Limits(meridian_west_deg=5.0)
    # 5° + 2.5° to go at 15.04°/h: 29.9 min.
    assert minutes_left(limits, -2.5 / 15.0, WEST) == pytest.approx(29.92, abs=0.01)
    assert minutes_left(limits, 6.0 / 15.0, WEST) == 0.0
    assert minutes_left(limits, -1.0, EAST) == float("inf")  # tracking moves away from it


def test_the_device_side_is_kept_when_it_tracks_long_enough() -> None:
    limits = Limits()
    assert plan_goto_side(limits, -1.0, WEST, can_choose=False) is None
    assert plan_goto_side(limits, 1.0, EAST, can_choose=False) is None
    # The simulator keeps the east side 3° east of the meridian (within its tolerance): fine.
    assert plan_goto_side(limits, -0.2, EAST, can_choose=True) is None


def test_a_side_too_short_or_past_the_limit_is_swapped_where_the_device_can_be_told() -> None:
    limits = Limits(meridian_east_deg=10.0, meridian_west_deg=5.0, min_track_minutes=60.0)
    assert plan_goto_side(limits, -0.5, WEST, can_choose=True) is EAST
    # The simulator staying on the west side 3° past the meridian: 8 min left < 60.
    assert plan_goto_side(limits, 0.2, WEST, can_choose=True) is EAST
    # Past the east limit on the east side: the west one.
    assert plan_goto_side(limits, -0.8, EAST, can_choose=True, tracking=False) is WEST


def test_a_device_that_picks_its_own_side_is_refused_in_one_line() -> None:
    limits = Limits(meridian_east_deg=10.0, meridian_west_deg=5.0, min_track_minutes=60.0)
    with pytest.raises(LimitError) as refused:
        plan_goto_side(limits, -0.5, WEST, can_choose=False)
    message = str(refused.value)
    assert "limits.min_track_minutes (60)" in message
    assert "in 50 min" in message
    assert "nothing was sent" in message
    assert "\n" not in message


def test_when_neither_side_tracks_long_enough_the_longer_one_within_the_limits() -> None:
    limits = Limits(meridian_east_deg=5.0, meridian_west_deg=5.0, min_track_minutes=60.0)
    assert plan_goto_side(limits, -8.0 / 15.0, WEST, can_choose=False) is None
    assert plan_goto_side(limits, -8.0 / 15.0, EAST, can_choose=True) is WEST


def test_a_flip_never_lands_on_the_side_it_leaves() -> None:
    limits = Limits(meridian_west_deg=5.0, min_track_minutes=0.0)
    # 1° past: the west side still tracks 16 min, but a flip leaves it.
    assert plan_goto_side(limits, 1.0 / 15.0, WEST, can_choose=True) is None
    assert plan_goto_side(limits, 1.0 / 15.0, WEST, can_choose=True, leave=WEST) is EAST
    with pytest.raises(LimitError, match="picks the pier side"):
        plan_goto_side(limits, 1.0 / 15.0, WEST, can_choose=False, leave=WEST)


@pytest.mark.parametrize(
    ("options", "setting"),
    [
        ({"meridian_west_deg": -1.0}, "meridian_west_deg"),
        ({"meridian_east_deg": 46.0}, "meridian_east_deg"),
        ({"meridian_east_deg": float("nan")}, "meridian_east_deg"),
        ({"min_track_minutes": 181.0}, "min_track_minutes"),
        ({"min_track_minutes": -0.5}, "min_track_minutes"),
        ({"auto_flip": 1}, "auto_flip"),
    ],
)
def test_out_of_range_settings_are_refused_naming_them(
    options: dict[str, object], setting: str
) -> None:
    with pytest.raises(InvalidValueError, match=setting):
        Limits(**options)  # type: ignore[arg-type]
