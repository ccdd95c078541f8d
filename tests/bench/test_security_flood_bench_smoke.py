"""The flood benchmark's goal line checks every row it claims (the measurement itself runs in
tests/test_security_access_flood.py)."""

from __future__ import annotations

from bench.security_flood import PROTOCOLS, FloodResult, goal_line


def result(ratio: float, errors: int = 0, counted_refusals: int = 86) -> FloodResult:
    tallies = {
        p: {"admitted": 64, "refused": 86, "answered": 5000, "too_many": 0, "errors": 0}
        for p in PROTOCOLS
    }
    tallies[PROTOCOLS[-1]]["errors"] = errors
    refused = dict.fromkeys(PROTOCOLS, 86)
    refused[PROTOCOLS[0]] = counted_refusals
    return FloodResult(40.0, 40.0 * ratio, tallies, refused)


def test_the_goal_passes_only_when_every_server_refused_cleanly() -> None:
    assert ": PASS (97.5 %, clean)" in goal_line(result(0.975))
    assert ": MISS (85.0 %, clean)" in goal_line(result(0.85))
    # One server's broken connection, or a refusal the server did not count, is a miss.
    assert ": MISS (97.5 %, NOT clean)" in goal_line(result(0.975, errors=1))
    assert ": MISS (97.5 %, NOT clean)" in goal_line(result(0.975, counted_refusals=85))
