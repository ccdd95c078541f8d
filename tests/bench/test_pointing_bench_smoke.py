"""The pointing benchmark still runs, prints its table and meets its goal in its quick case."""

from __future__ import annotations

import pytest

from tests.support.quick_bench import assert_provenance, run_quick_bench


@pytest.mark.timeout(120)
def test_quick_pointing_benchmark_prints_its_table_and_goal() -> None:
    stdout = run_quick_bench("bench.pointing", timeout_s=120).stdout
    assert_provenance(stdout)
    lines = stdout.splitlines()
    assert lines[2].startswith("mount    misalignment")
    assert lines[3].startswith("EQ6 ")
    assert lines[-1].startswith("goal: after 6 syncs, gotos to 20 other stars within 2′ RMS")
    assert lines[-1].endswith(": met")
