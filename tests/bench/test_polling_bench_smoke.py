"""The polling benchmark still runs, prints its rows and meets its goals (so it cannot rot)."""

from __future__ import annotations

from tests.support.quick_bench import run_quick_bench


def test_quick_polling_benchmark_prints_its_rows() -> None:
    result = run_quick_bench("bench.polling", timeout_s=120)
    lines = result.stdout.splitlines()
    assert lines[1].split()[:3] == ["driver", "device", "client"]
    assert [line.split()[:3] for line in lines[2:4]] == [
        ["synscan", "9600", "none"],
        ["synscan", "instant", "alpaca10"],
    ]
    assert all(line.endswith("met") for line in lines[2:]), result.stdout
