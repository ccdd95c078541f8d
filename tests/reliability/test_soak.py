"""A short soak (1 simulated hour at x200, 18 s real): ``python -m bench.soak --quick`` run as a
user runs it, which also keeps the benchmark from rotting.

The emulated SynScan (its own process) meets one fault of each cheap kind early in the night
(the connection closed, a malformed reply, a slow reply, a reply 6 s late); ``scopelink serve``
drives it while Alpaca, LX200, Stellarium, SynScan and dashboard clients poll and command. Every
check the full night makes must pass here too (bounds in ``bench/soak.py``).
"""

from __future__ import annotations

import logging
import re
import tracemalloc
from collections.abc import Callable

import pytest

from scopelink.decode import Protocol
from scopelink.web.traffic import TrafficMonitor
from tests.support.quick_bench import run_quick_bench

CHECKS = (
    "every fault kind fired",
    "no request unanswered, no connection broken",
    "no stuck slew",
    "poller never stops",
    "recovers after faults",
    "final slew lands",
    "tube within its meridian limit (device's sky)",
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


# --- what the soak found: the dashboard's traffic panel kept state per byte and per connection ---


def _trace(monitor: TrafficMonitor, link: str, arrow: str, data: bytes) -> None:
    hex_bytes = " ".join(f"{byte:02x}" for byte in data)
    message = f"{link} {arrow} {len(data)} bytes: {hex_bytes} | {data!r}"
    monitor.emit(
        logging.LogRecord("scopelink.links.trace", logging.DEBUG, "", 0, message, (), None)
    )


def _traced_growth(warm_up: Callable[[], None], work: Callable[[], None]) -> int:
    """Bytes allocated by scopelink's code and held after ``work`` that were not after
    ``warm_up`` (which fills what is meant to fill: the kept lines, the decoded links)."""
    ours = (tracemalloc.Filter(True, "*/scopelink/*"),)
    tracemalloc.start()
    try:
        warm_up()
        before = tracemalloc.take_snapshot().filter_traces(ours)
        work()
        after = tracemalloc.take_snapshot().filter_traces(ours)
    finally:
        tracemalloc.stop()
    return sum(stat.size_diff for stat in after.compare_to(before, "filename"))


@pytest.mark.parametrize(
    ("protocol", "command", "reply"),
    [
        (Protocol.SYNSCAN, b"e", b"34AB0500,12CE0500#"),
        (Protocol.SKYTRACKER, b"Q", b"A"),
    ],
)
def test_the_traffic_panel_keeps_nothing_per_byte_of_a_live_link(
    protocol: Protocol, command: bytes, reply: bytes
) -> None:
    """The decoder kept every byte's position for the life of the link: ~10 MiB an hour of RSS
    in the soak (serve's poller sends ~50 SynScan commands a second)."""
    monitor = TrafficMonitor(protocol)
    link = "tcp://127.0.0.1:11880"

    def exchanges(count: int) -> Callable[[], None]:
        def run() -> None:
            for _ in range(count):
                _trace(monitor, link, "-->", command)
                _trace(monitor, link, "<--", reply)

        return run

    # The warm-up also fills the codec's bounded caches (flat after ~2,500 exchanges). A few kB
    # come and go with the interpreter's own small caches (up to ~7 kB seen, whatever the
    # count), so the work is long enough for a leak of 1 byte per exchange to stand out.
    assert _traced_growth(exchanges(2_500), exchanges(10_000)) < 10_000  # was ~400 kB


def test_the_traffic_panel_forgets_links_of_clients_long_gone() -> None:
    monitor = TrafficMonitor(Protocol.SYNSCAN)

    def connections(first: int, count: int) -> Callable[[], None]:
        def run() -> None:
            for port in range(first, first + count):
                _trace(monitor, f"tcp 127.0.0.1:{port} on :11880", "<--", b"e")

        return run

    assert _traced_growth(connections(20_000, 3_000), connections(30_000, 1_000)) < 5_000
