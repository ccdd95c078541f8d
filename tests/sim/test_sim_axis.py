"""Axis motion: closed form, exact landings, limits, and independence from how often one looks."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.sim import Axis, SimClock, plan_move

MAX_RATE = 3.4
ACCELERATION = 3.4


def make_axis(*, wrap: bool = False, position: float = 0.0) -> tuple[SimClock, Axis]:
    clock = SimClock.stepped()
    axis = Axis(
        "test",
        max_rate_deg_s=MAX_RATE,
        acceleration_deg_s2=ACCELERATION,
        time_source=clock.elapsed,
        position_deg=position,
        wrap=wrap,
    )
    return clock, axis


def busy_plan(axis: Axis) -> None:
    """A mixture of ramps, a reversal, a cruise and a slew, planned ahead of time."""
    axis.set_rate(2.0, at=0.0)
    axis.set_rate(-1.5, at=3.0)
    axis.slew_to(40.0, at=6.0)
    axis.set_rate(0.7, at=30.0)
    axis.stop(at=33.3)


def test_closed_form_equals_fine_numeric_integration() -> None:
    _, axis = make_axis()
    busy_plan(axis)
    boundaries = sorted(s.start_s for s in axis.segments)
    dt = 1e-3
    position, rate, t = 0.0, 0.0, 0.0
    for step in range(1, 40_001):
        end = step * dt
        # Split the step where the acceleration changes, then integrate each piece.
        cuts = [b for b in boundaries if t < b < end]
        for piece_end in [*cuts, end]:
            h = piece_end - t
            acceleration = axis.segment_at(t + h / 2).acceleration_deg_s2
            position += rate * h + 0.5 * acceleration * h * h
            rate += acceleration * h
            t = piece_end
        if step % 997 == 0:
            assert axis.unwrapped_position_at(t) == pytest.approx(position, abs=1e-9)
            assert axis.rate_at(t) == pytest.approx(rate, abs=1e-9)


def test_closed_form_matches_numeric_integration_of_its_own_rate() -> None:
    _, axis = make_axis()
    busy_plan(axis)
    # Trapezoidal integration of the rate converges to the closed form (error ~ dt²).
    dt = 1e-3
    position = 0.0
    previous_rate = axis.rate_at(0.0)
    for step in range(1, 36_001):
        rate = axis.rate_at(step * dt)
        position += 0.5 * (rate + previous_rate) * dt
        previous_rate = rate
    assert position == pytest.approx(axis.unwrapped_position_at(36.0), abs=1e-5)


def test_reading_at_1_hz_and_1000_hz_gives_identical_positions() -> None:
    readings = {}
    # 1024 Hz: steps of 2**-10 s add up exactly, so both clocks read the same instants.
    for hz in (1, 1024):
        clock, axis = make_axis()
        busy_plan(axis)
        seen = {}
        for step in range(40 * hz + 1):
            if step:
                clock.advance(1.0 / hz)
            if step % hz == 0:
                seen[step // hz] = (axis.position, axis.rate)
        readings[hz] = seen
    for second, (position, rate) in readings[1].items():
        assert readings[1024][second] == (position, rate)


def test_position_does_not_depend_on_reads_in_between() -> None:
    clock, looked_at = make_axis()
    _, untouched = make_axis()
    busy_plan(looked_at)
    busy_plan(untouched)
    for _ in range(5000):
        clock.advance(0.007)
        looked_at.position  # noqa: B018 - reading must not change anything
    t = clock.elapsed()
    assert looked_at.position_at(t) == untouched.position_at(t)


def test_trapezoid_lands_exactly_and_respects_limits() -> None:
    _, axis = make_axis(position=10.0)
    landing = axis.slew_to(100.0, at=0.0)
    # Ramp 1 s (1.7°), cruise (90 - 3.4) / 3.4 s, ramp 1 s.
    assert landing == pytest.approx(2.0 + (90.0 - 3.4) / 3.4, abs=1e-12)
    assert axis.unwrapped_position_at(landing) == 100.0
    assert axis.rate_at(landing) == 0.0
    assert axis.unwrapped_position_at(landing + 100.0) == 100.0
    for segment in axis.segments:
        assert abs(segment.acceleration_deg_s2) <= ACCELERATION
        assert abs(segment.rate_deg_s) <= MAX_RATE + 1e-12
    samples = [landing * k / 1000 for k in range(1001)]
    assert max(abs(axis.rate_at(t)) for t in samples) == pytest.approx(MAX_RATE)


def test_short_slew_is_a_triangle() -> None:
    _, axis = make_axis()
    landing = axis.slew_to(0.85, at=0.0)
    assert landing == pytest.approx(2.0 * math.sqrt(0.85 / ACCELERATION), abs=1e-12)
    assert axis.unwrapped_position_at(landing) == 0.85
    assert max(abs(axis.rate_at(landing * k / 100)) for k in range(101)) < MAX_RATE


def test_set_rate_ramps_and_stop_ramps_down() -> None:
    _, axis = make_axis()
    end = axis.set_rate(-3.4, at=0.0)
    assert end == pytest.approx(1.0)
    assert axis.rate_at(0.5) == pytest.approx(-1.7)
    assert axis.unwrapped_position_at(1.0) == pytest.approx(-1.7)
    rest = axis.stop(at=5.0)
    assert rest == pytest.approx(6.0)
    assert axis.unwrapped_position_at(6.0) == pytest.approx(-1.7 - 4 * 3.4 - 1.7)
    assert not axis.is_moving_at(6.5)
    with pytest.raises(ValueError, match="exceeds the limit"):
        axis.set_rate(3.5)


def test_slew_while_moving_away_turns_back_and_lands() -> None:
    _, axis = make_axis()
    axis.set_rate(3.4, at=0.0)
    landing = axis.slew_to(0.0, at=2.0)  # moving at full speed away from the target
    assert axis.unwrapped_position_at(landing) == 0.0
    assert all(abs(s.acceleration_deg_s2) <= ACCELERATION for s in axis.segments)


def test_wrapping_axis_takes_the_short_way_and_reports_0_to_360() -> None:
    _, axis = make_axis(wrap=True, position=350.0)
    landing = axis.slew_to(10.0, at=0.0)
    assert axis.unwrapped_position_at(landing) == pytest.approx(370.0)
    assert axis.position_at(landing) == pytest.approx(10.0)
    assert max(axis.unwrapped_position_at(landing * k / 50) for k in range(51)) <= 370.0 + 1e-9


def test_set_position_redefines_the_counter_without_moving() -> None:
    clock, axis = make_axis()
    axis.set_rate(1.0, at=0.0)
    clock.advance(5.0)
    before = axis.physical_position_at(8.0)
    axis.set_position(200.0)
    assert axis.position == pytest.approx(200.0)
    assert axis.physical_position_at(8.0) == pytest.approx(before)
    assert axis.rate == pytest.approx(1.0)


def test_follow_and_insert_follow_are_continuous() -> None:
    _, axis = make_axis()
    axis.follow(lambda t: 100.0 + 0.01 * t, at=0.0)
    assert axis.unwrapped_position_at(5.0) == pytest.approx(0.05)
    axis.set_rate(0.5, at=10.0)
    axis.insert_follow(lambda t: 0.03 * t, at=20.0)
    axis.insert_follow(lambda t: 5.0 + 0.02 * t, at=12.0)  # ahead of the one at 20 s
    for t in (12.0, 20.0):
        assert axis.unwrapped_position_at(t) == pytest.approx(
            axis.unwrapped_position_at(t - 1e-9), abs=1e-8
        )
    assert axis.rate_at(13.0) == pytest.approx(0.5 + 0.02, abs=1e-9)
    assert axis.rate_at(21.0) == pytest.approx(0.5 + 0.03, abs=1e-9)
    axis.insert_follow(None, at=30.0)
    assert axis.rate_at(31.0) == pytest.approx(0.5, abs=1e-12)
    rest = axis.stop(at=40.0)
    assert not axis.is_moving_at(rest)
    assert axis.unwrapped_position_at(rest + 5.0) == axis.unwrapped_position_at(rest)


def test_stop_takes_over_a_followed_rate() -> None:
    _, axis = make_axis()
    axis.follow(lambda t: 0.004 * t, at=0.0)
    rest = axis.stop(at=100.0)
    assert rest == pytest.approx(100.0 + 0.004 / ACCELERATION)
    assert axis.unwrapped_position_at(rest) == pytest.approx(0.4 + 0.004**2 / (2 * ACCELERATION))


@settings(max_examples=300, deadline=None)
@given(
    start=st.floats(-500.0, 500.0),
    start_rate=st.floats(-MAX_RATE, MAX_RATE),
    target=st.floats(-500.0, 500.0),
    max_rate=st.floats(0.01, MAX_RATE),
)
def test_random_slews_land_exactly_when_predicted(
    start: float, start_rate: float, target: float, max_rate: float
) -> None:
    _, axis = make_axis(position=start)
    axis.set_rate(start_rate, at=-10.0)  # already turning at start_rate by t = 0
    position0 = axis.unwrapped_position_at(0.0)
    phases = plan_move(target - position0, start_rate, max_rate, ACCELERATION)
    landing = axis.slew_to(target, max_rate_deg_s=max_rate, at=0.0)
    assert landing == pytest.approx(sum(p.duration_s for p in phases), rel=1e-12, abs=1e-12)
    assert axis.unwrapped_position_at(landing) == target
    assert axis.rate_at(landing) == 0.0
    peak = max(abs(start_rate), max_rate)
    for k in range(101):
        t = landing * k / 100
        assert abs(axis.rate_at(t)) <= peak * (1 + 1e-9) + 1e-12
    assert all(abs(s.acceleration_deg_s2) <= ACCELERATION for s in axis.segments)
    # Continuity: no jump anywhere in the plan.
    for segment in axis.segments[1:]:
        just_before = axis.unwrapped_position_at(segment.start_s - 1e-9)
        assert axis.unwrapped_position_at(segment.start_s) == pytest.approx(just_before, abs=1e-7)


@settings(max_examples=200, deadline=None)
@given(distance=st.floats(1e-6, 1000.0), max_rate=st.floats(0.01, MAX_RATE))
def test_slews_from_rest_take_the_textbook_time(distance: float, max_rate: float) -> None:
    duration = sum(p.duration_s for p in plan_move(distance, 0.0, max_rate, ACCELERATION))
    if distance >= max_rate * max_rate / ACCELERATION:  # trapezoid
        expected = distance / max_rate + max_rate / ACCELERATION
    else:  # triangle
        expected = 2.0 * math.sqrt(distance / ACCELERATION)
    assert duration == pytest.approx(expected, rel=1e-9)
