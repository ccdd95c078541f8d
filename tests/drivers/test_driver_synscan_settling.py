"""Properties of the goto-completion fallback (firmware whose L sticks after an Alt-Az goto) and of
the resynchronising echoes."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from scopelink.drivers.synscan.exchange import SynScanWire
from scopelink.drivers.synscan.settling import NEAR_TARGET_DEG, STILL_DEG, SettleDetector

altitudes = st.floats(-80.0, 80.0)
azimuths = st.floats(0.0, 359.0)


@given(altitudes, azimuths, st.lists(st.floats(0.01, 5.0), min_size=1, max_size=30))
def test_a_moving_mount_never_counts_as_settled(alt: float, az: float, steps: list[float]) -> None:
    detector = SettleDetector(alt, az, started_at_s=0.0, timeout_s=0.0)
    for index, step in enumerate(steps):
        # Each reading is well over STILL_DEG from the previous one (the sign alternates).
        az += step if index % 2 else -step
        assert step > STILL_DEG
        assert not detector.update(alt, az % 360.0, now_s=1000.0)


@given(
    altitudes,
    azimuths,
    st.floats(0.0, NEAR_TARGET_DEG * 0.9),
    st.floats(0.0, STILL_DEG * 0.4),
)
def test_standing_still_near_the_target_settles_on_the_third_reading(
    alt: float, az: float, offset: float, jitter: float
) -> None:
    detector = SettleDetector(alt, az, started_at_s=0.0)
    readings = [(alt + offset, az), (alt + offset + jitter, az), (alt + offset, az)]
    results = [detector.update(a, z, now_s=1.0) for a, z in readings]
    assert results == [False, False, True]
    assert detector.update(alt - 40.0, az, now_s=2.0)  # and stays settled


@given(altitudes, azimuths, st.floats(1.0, 30.0), st.floats(0.0, 600.0))
def test_standing_still_away_from_the_target_settles_only_after_the_timeout(
    alt: float, az: float, away: float, now: float
) -> None:
    detector = SettleDetector(alt, az, started_at_s=0.0, timeout_s=300.0)
    stopped = min(alt + away, 89.0) if alt < 0 else alt - away
    results = [detector.update(stopped, az, now_s=now) for _ in range(3)]
    assert results[:2] == [False, False]
    assert results[2] is (now >= 300.0)


@given(st.sets(st.integers(0x80, 0xFF), max_size=100))
def test_resynchronising_echoes_are_unique_and_avoid_reserved_bytes(avoid: set[int]) -> None:
    async def never_opened() -> None:  # pragma: no cover - nothing is opened here
        raise AssertionError

    wire = SynScanWire(never_opened, name="test")  # type: ignore[arg-type]
    wire.avoid_echo = avoid
    free = 128 - len(avoid)
    values = [wire._echo_value() for _ in range(free)]
    assert len(set(values)) == free
    assert all(0x80 <= value <= 0xFF and value not in avoid for value in values)
