"""The persistence benchmark still runs and prints its table (so the benchmark code cannot rot)."""

from __future__ import annotations

import pytest

from tests.support.quick_bench import assert_provenance, run_quick_bench


@pytest.mark.timeout(60)
def test_quick_persistence_benchmark_prints_its_table() -> None:
    stdout = run_quick_bench("bench.persistence", timeout_s=60).stdout
    assert_provenance(stdout)
    lines = stdout.splitlines()
    assert lines[2].startswith("median (best) per write, 3 writes each")
    for name in ("settings file", "object store (59 slots)", "UniqueID"):
        assert any(line.startswith(name) and line.endswith("x") for line in lines), name
    assert lines[-1].startswith("'scopelink config set' in process:")
