"""The Sky Tracker driver's rate mapping (move_axis), guide buttons and timed presses (custom
rates), the loop's guide-pulse shifts: pure functions; and the docs state the loop's settings."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.drivers.skytracker import axis_motion, guide_button, plan_buttons
from scopelink.drivers.skytracker.motion import (
    GUIDE_SPEED_MAX_ARCSEC_S,
    MAX_SKYTRACKER_TRACKING_OFFSET_ARCSEC_S,
    TRACK_ARROW_ARCSEC_S,
    UTILITY_ARROW_ARCSEC_S,
)
from scopelink.drivers.skytracker.presses import (
    MIN_PRESS_ARCSEC_S,
    PRESS_PERIOD_S,
    SPEED_HEADROOM,
    plan_press,
)
from scopelink.drivers.skytracker.rates import (
    FEED_FORWARD_STEP_S,
    LOOP_GAIN_PER_S,
    LOOP_INTEGRAL_GAIN,
    MAX_CORRECTION_ARCSEC_S,
)
from scopelink.mount import GuideDirection, MountAxis
from scopelink.mount.rates import ERRORS_KEPT, GuideShifts, RateLoopStatistics
from scopelink.protocol.skytracker import Direction, TrackerMode

SUPPORTED_ABOVE_GUIDE = (GUIDE_SPEED_MAX_ARCSEC_S, TRACK_ARROW_ARCSEC_S, UTILITY_ARROW_ARCSEC_S)


def test_rates_map_to_the_nearest_supported() -> None:
    guide = axis_motion(MountAxis.PRIMARY, 100.4 / 3600.0)
    assert guide is not None
    assert guide.mode is TrackerMode.GUIDE
    assert guide.guide_speed_arcsec_s == 100
    assert guide.direction is Direction.RIGHT
    tiny = axis_motion(MountAxis.SECONDARY, -0.1 / 3600.0)
    assert tiny is not None
    assert tiny.guide_speed_arcsec_s == 1
    assert tiny.direction is Direction.DOWN
    track = axis_motion(MountAxis.PRIMARY, -400.0 / 3600.0)
    assert track is not None
    assert track.mode is TrackerMode.TRACK
    assert track.rate_deg_s == pytest.approx(-8.0 / 60.0)
    assert track.direction is Direction.LEFT
    near_guide = axis_motion(MountAxis.PRIMARY, 300.0 / 3600.0)
    assert near_guide is not None
    assert near_guide.guide_speed_arcsec_s == 255
    utility = axis_motion(MountAxis.SECONDARY, 2.1)
    assert utility is not None
    assert utility.mode is TrackerMode.UTILITY
    assert axis_motion(MountAxis.PRIMARY, 0.0) is None


@given(
    axis=st.sampled_from(MountAxis),
    rate_deg_s=st.floats(min_value=-4.0, max_value=4.0, allow_nan=False).filter(bool),
)
def test_every_rate_maps_to_the_nearest_supported_one(axis: MountAxis, rate_deg_s: float) -> None:
    motion = axis_motion(axis, rate_deg_s)
    assert motion is not None
    assert (motion.rate_deg_s > 0) == (rate_deg_s > 0)  # never the wrong way
    positive = Direction.RIGHT if axis is MountAxis.PRIMARY else Direction.UP
    assert (motion.direction is positive) == (rate_deg_s > 0)
    speed = abs(rate_deg_s) * 3600.0
    given_speed = abs(motion.rate_deg_s) * 3600.0
    if speed <= GUIDE_SPEED_MAX_ARCSEC_S:
        assert motion.mode is TrackerMode.GUIDE
        assert motion.guide_speed_arcsec_s is not None
        assert abs(given_speed - speed) <= max(0.5, 1.0 - speed) + 1e-9
    else:
        nearest = min(abs(supported - speed) for supported in SUPPORTED_ABOVE_GUIDE)
        assert abs(given_speed - speed) == pytest.approx(nearest)
    if motion.mode is TrackerMode.GUIDE:
        assert motion.guide_speed_arcsec_s is not None
        assert 1 <= motion.guide_speed_arcsec_s <= GUIDE_SPEED_MAX_ARCSEC_S
        assert given_speed == pytest.approx(motion.guide_speed_arcsec_s)
    else:
        assert motion.guide_speed_arcsec_s is None


def test_guide_directions_press_one_arrow_each() -> None:
    assert guide_button(GuideDirection.NORTH) == (MountAxis.SECONDARY, Direction.UP)
    assert guide_button(GuideDirection.SOUTH) == (MountAxis.SECONDARY, Direction.DOWN)
    assert guide_button(GuideDirection.EAST) == (MountAxis.PRIMARY, Direction.LEFT)
    assert guide_button(GuideDirection.WEST) == (MountAxis.PRIMARY, Direction.RIGHT)


def test_button_plan_returns_to_the_mode_from_before() -> None:
    up_fast = axis_motion(MountAxis.SECONDARY, 4.0)
    assert up_fast is not None
    moving = plan_buttons(
        {MountAxis.SECONDARY: up_fast},
        {},
        pulse_speeds_arcsec_s=(120, 120),
        mode=TrackerMode.TRACK,
        rest_mode=None,
    )
    assert moving.mode is TrackerMode.UTILITY
    assert moving.pressed == (Direction.UP,)
    assert moving.rest_mode is TrackerMode.TRACK
    stopped = plan_buttons(
        {}, {}, pulse_speeds_arcsec_s=(120, 120), mode=moving.mode, rest_mode=moving.rest_mode
    )
    assert stopped.mode is TrackerMode.TRACK
    assert stopped.pressed == ()
    assert stopped.rest_mode is None


def test_button_plan_guides_at_the_pulse_speed_beside_a_guide_rate_motion() -> None:
    slow_right = axis_motion(MountAxis.PRIMARY, 30.0 / 3600.0)
    assert slow_right is not None
    plan = plan_buttons(
        {MountAxis.PRIMARY: slow_right},
        {MountAxis.SECONDARY: Direction.DOWN},
        pulse_speeds_arcsec_s=(60, 45),
        mode=TrackerMode.TRACK,
        rest_mode=None,
    )
    assert plan.mode is TrackerMode.GUIDE
    assert plan.guide_speeds_arcsec_s == (30, 45)  # azimuth held at 30, elevation pulses at 45
    assert plan.all_pressed == Direction.RIGHT | Direction.DOWN
    pulses_only = plan_buttons(
        {},
        {MountAxis.PRIMARY: Direction.LEFT},
        pulse_speeds_arcsec_s=(60, 45),
        mode=TrackerMode.TRACK,
        rest_mode=None,
    )
    assert pulses_only.mode is TrackerMode.GUIDE
    assert pulses_only.guide_speeds_arcsec_s == (60, 45)


def test_timed_presses_give_the_mean_rate_with_a_kept_speed() -> None:
    press = plan_press(MountAxis.SECONDARY, -12.4, 120)
    assert press is not None
    assert press.direction is Direction.DOWN
    assert press.speed_arcsec_s == 15  # 12.4 x 1.15, rounded up: 120 does not fit
    assert press.speed_arcsec_s * press.duty == pytest.approx(12.4)
    kept = plan_press(MountAxis.SECONDARY, -13.0, press.speed_arcsec_s)
    assert kept is not None
    assert kept.speed_arcsec_s == 15  # still fits: K is not sent again
    tiny = plan_press(MountAxis.PRIMARY, 0.3, 15)
    assert tiny is not None
    assert (tiny.speed_arcsec_s, tiny.direction) == (1, Direction.RIGHT)
    assert tiny.duty == pytest.approx(0.3)
    assert plan_press(MountAxis.PRIMARY, 0.01, 15) is None  # below MIN_PRESS_ARCSEC_S
    fast = plan_press(MountAxis.PRIMARY, -400.0, 15)
    assert fast is not None
    assert fast.saturated
    assert (fast.speed_arcsec_s, fast.duty) == (GUIDE_SPEED_MAX_ARCSEC_S, 1.0)


def test_guide_shifts_grow_while_a_pulse_runs_and_a_new_one_cuts_it() -> None:
    shifts = GuideShifts()
    shifts.add(1, 10.0, 4.0, 0.0, 0.5)
    assert shifts.at(9.0) == (0.0, 0.0)
    assert shifts.at(12.0) == pytest.approx((0.0, 1.0))
    assert shifts.rates_at(12.0) == (0.0, 0.5)
    shifts.add(1, 13.0, 1.0, 0.0, -0.5)  # the same axis: the first ends at 13
    assert shifts.at(20.0) == pytest.approx((0.0, 1.5 - 0.5))
    assert shifts.rates_at(13.5) == (0.0, -0.5)


def test_the_tracking_page_states_the_sky_tracker_loop_settings() -> None:
    tracking = (Path(__file__).resolve().parents[2] / "docs" / "tracking.md").read_text("utf-8")
    assert f"`LOOP_GAIN_PER_S` = {LOOP_GAIN_PER_S:g} /s" in tracking
    assert f"±`MAX_CORRECTION_ARCSEC_S` ({MAX_CORRECTION_ARCSEC_S:g}″/s)" in tracking
    assert f"`PRESS_PERIOD_S` ({PRESS_PERIOD_S:g} s" in tracking
    assert f"`SPEED_HEADROOM` ({SPEED_HEADROOM:g})" in tracking
    assert f"`MIN_PRESS_ARCSEC_S` ({MIN_PRESS_ARCSEC_S:g}″/s)" in tracking
    assert f"`FEED_FORWARD_STEP_S` ({FEED_FORWARD_STEP_S:g} s)" in tracking
    assert LOOP_INTEGRAL_GAIN == LOOP_GAIN_PER_S**2 / 4.0  # "gain²/4"
    assert f"±{MAX_SKYTRACKER_TRACKING_OFFSET_ARCSEC_S:g}″/s of RA and Dec" in tracking


def test_a_loop_keeps_the_errors_of_its_last_readings_only() -> None:
    statistics = RateLoopStatistics()
    for index in range(2 * ERRORS_KEPT + 1):
        statistics.add_error(float(index))
    assert len(statistics.errors_arcsec) == ERRORS_KEPT
    assert statistics.errors_arcsec[-1] == 2 * ERRORS_KEPT
