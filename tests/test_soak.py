"""A short soak (1 simulated hour at x200, 18 s real): ``python -m bench.soak --quick`` run as a
user runs it, which also keeps the benchmark from rotting.

The emulated SynScan (its own process) meets one fault of each cheap kind early in the night
(the connection closed, a malformed reply, a slow reply, a reply 6 s late); ``scopelink serve``
drives it while Alpaca, LX200, Stellarium, SynScan and dashboard clients poll and command. Every
check the full night makes must pass here too (bounds in ``bench/soak.py``).
"""

from __future__ import annotations

import re

import pytest

from tests.bench_support import run_quick_bench

CHECKS = (
    "every fault kind fired",
    "no request unanswered, no connection broken",
    "no stuck slew",
    "poller never stops",
    "recovers after faults",
    "final slew lands",
    "Stellarium stream steady",
    "memory flat",
    "fds flat, back to baseline",
    "clean exits",
)


@pytest.mark.timeout(90)
def test_a_short_night_under_faults_passes_every_check() -> None:
    result = run_quick_bench(
        "bench.soak", timeout_s=90
    )  # fails on a non-zero exit (a failed check)
    out = result.stdout
    for name in CHECKS:
        assert re.search(rf"^check {re.escape(name)}: ok - ", out, re.MULTILINE), out
    assert out.rstrip().endswith("soak PASSED"), out

    # The night really had its load and its faults: every protocol was used...
    requests = dict(re.findall(r"^(\w+) +(\d+) +\d+ +[\d.]+ +0(?:  .*)?$", out, re.MULTILINE))
    assert set(requests) == {"alpaca", "dashboard", "lx200", "stellarium", "synscan"}, out
    assert all(int(count) >= 20 for count in requests.values()), requests
    # ... each scripted fault fired, and slews were made and ended
    fired = re.search(r"^faults fired (\d+): (.*)$", out, re.MULTILINE)
    assert fired, out
    assert fired.group(2) == "close 1, delay=6 1, malformed 1, slow 1"
    slews = re.search(r"^slews (\d+);", out, re.MULTILINE)
    assert slews, out
    assert int(slews.group(1)) >= 1
