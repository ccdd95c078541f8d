"""The fault-recovery benchmark's command line runs (provenance first) and its figures are the
worst of its trials (the tables themselves: tests/test_fault_matrix_synscan.py)."""

from __future__ import annotations

import pytest
from bench.fault_recovery_synscan import Result, worst

from tests.support.quick_bench import assert_provenance, run_quick_bench


@pytest.mark.timeout(60)
def test_quick_run_prints_where_its_figures_come_from() -> None:
    result = run_quick_bench("bench.fault_recovery_synscan", timeout_s=60)
    assert_provenance(result.stdout)
    assert result.stdout.splitlines()[2].endswith("worst of 1 trial(s)"), result.stdout


def test_a_case_shows_its_worst_trial() -> None:
    trials = [Result("drop", "recovered", 5.2, 0.03), Result("drop", "recovered", 5.1, 0.2)]
    assert worst(trials) == Result("drop", "recovered", 5.2, 0.2)
    trials.append(Result("drop", "error", 5.0, 0.01))
    assert worst(trials).outcome == "mixed"
