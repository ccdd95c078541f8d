"""The polling benchmark still runs, prints its rows and meets its goals (so it cannot rot)."""

from __future__ import annotations

from tests.support.quick_bench import assert_provenance, run_quick_bench


def test_quick_polling_benchmark_prints_its_rows() -> None:
    result = run_quick_bench("bench.polling", timeout_s=120)
    lines = result.stdout.splitlines()
    assert_provenance(result.stdout)
    header = next(
        i for i, line in enumerate(lines) if line.split()[:3] == ["driver", "device", "client"]
    )
    assert "best of 1 round" in lines[header - 1], result.stdout
    assert [line.split()[:3] for line in lines[header + 1 : header + 3]] == [
        ["synscan", "9600", "none"],
        ["synscan", "instant", "alpaca10"],
    ]
    assert all(line.endswith("met") for line in lines[header + 1 :]), result.stdout
