"""The Sky Tracker driver benchmark still runs and prints its tables (so the code cannot rot)."""

from __future__ import annotations

import os
import re

import pytest
from bench.provenance import UVLOOP_PIN

from tests.support.quick_bench import assert_provenance, run_quick_bench


# Solo: its short blocks (3 polls) are timed against the wire, and a paced line catching up
# after a late wake-up (a busy neighbour) reads faster than the wire over so short a window.
@pytest.mark.solo
@pytest.mark.timeout(90)
def test_quick_benchmark_prints_its_tables() -> None:
    result = run_quick_bench("bench.drivers_skytracker", timeout_s=90)
    assert_provenance(result.stdout)
    lines = result.stdout.splitlines()
    assert lines[3] == f"serve's event loop: uvloop {UVLOOP_PIN} (pin {UVLOOP_PIN})"
    wire = [line for line in lines if line.startswith("position poll") and line.endswith("%")]
    assert len(wire) == 1, result.stdout
    driver, bare, limit = (float(field) for field in wire[0].split()[-5:-2])
    assert 0 < driver <= limit * 1.02  # the emulated line never beats the wire
    assert 0 < bare <= limit * 1.02
    assert any(line.startswith("status (R)") and line.endswith("x") for line in lines)
    # The CPU rows time the client's side only: the emulators run in another (spawned) process on
    # TCP 127.0.0.1, on another CPU where there are two, as a real Sky Tracker is another machine.
    placement = [line for line in lines if line.startswith("processes: ")]
    assert len(placement) == 1, result.stdout
    found = re.fullmatch(
        r"processes: bench pid (\d+), client threads on CPU (\S+); emulators pid (\d+) on CPU "
        r"(\S+), tcp://127\.0\.0\.1:\d+ and tcp://127\.0\.0\.1:\d+",
        placement[0],
    )
    assert found is not None, placement
    bench_pid, client_cpu, emulator_pid, emulator_cpu = found.groups()
    assert bench_pid != emulator_pid, placement
    if len(os.sched_getaffinity(0)) >= 2:
        assert client_cpu != emulator_cpu, placement
    assert any(
        line.startswith("CPU per command, TCP, emulators in another process") for line in lines
    )
    # One verdict for every CPU row the goal (issue #14 part 2) speaks for.
    goals = [line for line in lines if line.startswith("goal ")]
    assert [line.split(":")[0] for line in goals] == [
        "goal position poll (Q \\r q)",
        "goal refresh (R + position)",
        "goal status (R)",
    ], result.stdout
    assert all(line.split(": ")[-1].split()[0] in {"PASS", "MISS"} for line in goals), goals
