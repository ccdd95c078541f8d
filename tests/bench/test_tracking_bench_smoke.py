"""The tracking benchmark's quick run: the Moon followed on the simulator, beside its peer."""

from __future__ import annotations

from tests.support.quick_bench import assert_provenance, run_quick_bench


def test_tracking_benchmark_quick_run_follows_the_moon() -> None:
    printed = run_quick_bench("bench.tracking", timeout_s=90).stdout
    assert_provenance(printed)
    (row,) = [line for line in printed.splitlines() if line.startswith("| sim | Moon |")]
    followed, peer = row.split(" | ")[2:4]
    assert float(followed.split("″ RMS")[0]) < 1.0, row
    assert float(peer.split("″ RMS")[0]) > 30.0, row  # sidereal alone drifts off the Moon
    assert "goal RMS <= 10″: met" in row
    assert printed.splitlines()[-1] == "goal: every figure within its goal: met"
